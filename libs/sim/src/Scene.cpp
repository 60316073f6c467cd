#include "IniHelpers.h"

#include <keygrid/sim/Random.h>
#include <keygrid/sim/Scene.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/system/filesystem.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <stdexcept>

namespace keygrid::sim
{
namespace
{
constexpr double kDeg = M_PI / 180.0;

/** Throws on a key of `section` that is not in `allowed` and matches none of `prefixes`. */
void checkKeys(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section,
	const std::set<std::string>& allowed, const std::vector<std::string>& prefixes = {})
{
	std::vector<std::string> keys;
	cfg.getAllKeys(section, keys);
	for (const auto& k : keys)
	{
		if (allowed.count(k)) continue;
		bool ok = false;
		for (const auto& p : prefixes) ok = ok || k.rfind(p, 0) == 0;
		if (!ok) throw std::invalid_argument("[" + section + "] unknown key '" + k + "'");
	}
}

Eigen::Matrix3d yawPitchRoll(double yaw, double pitch, double roll)
{
	return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
			Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
			Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
		.toRotationMatrix();
}

void loadObject(
	const mrpt::config::CConfigFileBase& cfg, const std::string& s, std::uint64_t sceneSeed,
	SceneObject& obj, TextureOptions& tex)
{
	checkKeys(
		cfg, s,
		{"type", "corner", "edge1", "edge2", "centre", "size", "radius", "height", "yaw", "pitch",
		 "roll", "texture", "texture_seed", "texture_size", "texture_resolution", "colour",
		 "dynamic", "visible"},
		{"path_"});
	obj.name = s.substr(std::string("object.").size());
	const std::string typeStr = ini::raw(cfg, s, "type");
	if (typeStr.empty()) throw std::invalid_argument("[" + s + "] missing key 'type'");
	try
	{
		obj.shape.type = shapeTypeFromString(typeStr);
	}
	catch (const std::invalid_argument& e)
	{
		throw std::invalid_argument("[" + s + "] " + e.what());
	}
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	auto vec3 = [&](const char* k) {
		const auto v = ini::readVector(cfg, s, k, 3, {});
		if (v.empty()) throw std::invalid_argument("[" + s + "] missing key '" + k + "'");
		return Eigen::Vector3d(v[0], v[1], v[2]);
	};
	auto positive = [&](const char* k) {
		const double v = ini::readDouble(cfg, s, k, -1, 0, 1e4);
		if (!(v > 0))
			throw std::invalid_argument(
				"[" + s + "] key '" + std::string(k) + "' must be given and > 0");
		return v;
	};
	if (obj.shape.type == ShapeType::Quad)
	{
		// A rectangle from one corner and two orthogonal edges; its normal is edge1 x edge2.
		const Eigen::Vector3d c = vec3("corner"), e1 = vec3("edge1"), e2 = vec3("edge2");
		if (e1.norm() < 1e-6 || e2.norm() < 1e-6)
			throw std::invalid_argument("[" + s + "] edge1 and edge2 must be non-zero");
		if (std::abs(e1.normalized().dot(e2.normalized())) > 1e-6)
			throw std::invalid_argument("[" + s + "] edge1 and edge2 must be orthogonal");
		T.linear().col(0) = e1.normalized();
		T.linear().col(1) = e2.normalized();
		T.linear().col(2) = e1.normalized().cross(e2.normalized());
		T.translation() = c + 0.5 * (e1 + e2);
		obj.shape.half = Eigen::Vector3d(0.5 * e1.norm(), 0.5 * e2.norm(), 0);
	}
	else
	{
		T.translation() = vec3("centre");
		T.linear() = yawPitchRoll(
			ini::readDouble(cfg, s, "yaw", 0, -3600, 3600) * kDeg,
			ini::readDouble(cfg, s, "pitch", 0, -3600, 3600) * kDeg,
			ini::readDouble(cfg, s, "roll", 0, -3600, 3600) * kDeg);
		if (obj.shape.type == ShapeType::Box)
		{
			const Eigen::Vector3d sz = vec3("size");
			if (!(sz.minCoeff() > 0)) throw std::invalid_argument("[" + s + "] size must be > 0");
			obj.shape.half = 0.5 * sz;
		}
		else
		{
			const double r = positive("radius"), h = positive("height");
			obj.shape.half = Eigen::Vector3d(r, r, 0.5 * h);
		}
	}
	obj.T_world_obj = T;

	tex.style = ini::raw(cfg, s, "texture").empty() ? tex.style : ini::raw(cfg, s, "texture");
	tex.seed =
		ini::readSeed(cfg, s, "texture_seed", hashKey(sceneSeed, hashString(obj.name.c_str())));
	tex.sizeMetres = ini::readDouble(cfg, s, "texture_size", tex.sizeMetres, 0.01, 1000);
	tex.resolution =
		static_cast<int>(ini::readInt(cfg, s, "texture_resolution", tex.resolution, 64, 4096));
	// Default base colour: a mid tone drawn from the texture seed, so objects differ.
	Rng rng(tex.seed ^ 0xC0104);
	std::vector<double> rgb = {rng.uniform(60, 200), rng.uniform(60, 200), rng.uniform(60, 200)};
	rgb = ini::readVector(cfg, s, "colour", 3, rgb);
	for (int k = 0; k < 3; k++)
	{
		if (!(rgb[k] >= 0 && rgb[k] <= 255))
			ini::fail(s, "colour", ini::raw(cfg, s, "colour"), "components must be in [0, 255]");
		tex.base[2 - k] = static_cast<std::uint8_t>(std::lround(rgb[k]));  // r g b -> B G R
	}
	try
	{
		tex.validate();
	}
	catch (const std::invalid_argument& e)
	{
		throw std::invalid_argument("[" + s + "] " + e.what());
	}

	obj.dynamic = ini::readBool(cfg, s, "dynamic", false);
	for (int i = 0; i < 1000; i++)
	{
		char key[16];
		std::snprintf(key, sizeof(key), "path_%02d", i);
		const std::string v = ini::raw(cfg, s, key);
		if (v.empty()) break;
		const auto x = ini::numbers(s, key, v);
		if (x.size() != 4 && x.size() != 5) ini::fail(s, key, v, "expected 't x y z [yaw_deg]'");
		PathKey k;
		k.t = x[0];
		k.position = {x[1], x[2], x[3]};
		k.yaw = x.size() == 5 ? x[4] * kDeg : 0.0;
		if (!obj.motion.path.empty() && !(k.t > obj.motion.path.back().t))
			ini::fail(s, key, v, "times must increase");
		obj.motion.path.push_back(k);
	}
	const std::string vis = ini::raw(cfg, s, "visible");
	if (!vis.empty())
	{
		const auto x = ini::numbers(s, "visible", vis);
		if (x.empty() || x.size() % 2) ini::fail(s, "visible", vis, "expected pairs 't0 t1 ...'");
		for (std::size_t i = 0; i < x.size(); i += 2)
		{
			if (!(x[i] < x[i + 1])) ini::fail(s, "visible", vis, "each interval needs t0 < t1");
			obj.motion.visible.emplace_back(x[i], x[i + 1]);
		}
	}
	if (!obj.dynamic && (!obj.motion.path.empty() || !obj.motion.visible.empty()))
		throw std::invalid_argument("[" + s + "] path_NN / visible need dynamic = true");
}
}  // namespace

void SceneOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	checkKeys(
		c, s,
		{"name", "seed", "frames", "rate_hz", "start_time", "camera", "light_direction",
		 "ambient"});
	if (const auto v = ini::raw(c, s, "name"); !v.empty()) name = v;
	seed = ini::readSeed(c, s, "seed", seed);
	frames = static_cast<unsigned int>(ini::readInt(c, s, "frames", frames, 1, 1000000));
	rateHz = ini::readDouble(c, s, "rate_hz", rateHz, 0.1, 1000);
	startTime = ini::readDouble(c, s, "start_time", startTime, 0, 1e10);
	if (const auto v = ini::raw(c, s, "camera"); !v.empty()) camera = v;
	const auto l = ini::readVector(
		c, s, "light_direction", 3, {lightDirection.x(), lightDirection.y(), lightDirection.z()});
	lightDirection = Eigen::Vector3d(l[0], l[1], l[2]);
	if (lightDirection.norm() < 1e-9)
		ini::fail(s, "light_direction", ini::raw(c, s, "light_direction"), "must be non-zero");
	ambient = ini::readDouble(c, s, "ambient", ambient, 0, 1);
}

void SceneOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	c.write(s, "name", name);
	c.write(s, "seed", std::to_string(seed));
	c.write(s, "frames", frames);
	c.write(s, "rate_hz", rateHz);
	char buf[64];
	std::snprintf(buf, sizeof(buf), "%.6f", startTime);
	c.write(s, "start_time", std::string(buf));
	c.write(s, "camera", camera);
	std::snprintf(
		buf, sizeof(buf), "%g %g %g", lightDirection.x(), lightDirection.y(), lightDirection.z());
	c.write(s, "light_direction", std::string(buf));
	c.write(s, "ambient", ambient);
}

void Scene::addObject(SceneObject obj, const TextureOptions& tex)
{
	for (std::size_t i = 0; i < textures.size(); i++)
		if (textures[i]->options() == tex)
		{
			obj.texture = i;
			objects.push_back(std::move(obj));
			return;
		}
	textures.push_back(std::make_shared<const Texture>(tex));
	obj.texture = textures.size() - 1;
	objects.push_back(std::move(obj));
}

bool Scene::staticBounds(Eigen::Vector3d& lo, Eigen::Vector3d& hi) const
{
	bool any = false;
	for (const auto& o : objects)
	{
		if (o.dynamic) continue;
		for (const auto& c : o.shape.boundingCorners())
		{
			const Eigen::Vector3d p = o.T_world_obj * c;
			lo = any ? lo.cwiseMin(p) : p;
			hi = any ? hi.cwiseMax(p) : p;
			any = true;
		}
	}
	return any;
}

Scene Scene::loadFromFile(const std::string& path, unsigned int framesOverride)
{
	if (!mrpt::system::fileExists(path))
		throw std::runtime_error("scene file '" + path + "' does not exist");
	mrpt::config::CConfigFile cfg(path);
	return loadFromConfig(cfg, path, framesOverride);
}

Scene Scene::loadFromConfig(
	const mrpt::config::CConfigFileBase& cfg, const std::string& sourceName,
	unsigned int framesOverride)
{
	Scene sc;
	std::vector<std::string> sections;
	cfg.getAllSections(sections);
	std::sort(sections.begin(), sections.end());  // object order independent of the file order
	std::vector<std::string> objectSections;
	for (const auto& s : sections)
	{
		if (s.rfind("object.", 0) == 0)
			objectSections.push_back(s);
		else if (
			s != "scene" && s != "camera" && s != "sensor" && s != "trajectory" && s != "output")
			throw std::invalid_argument(
				sourceName + ": unknown section [" + s +
				"] (expected scene, camera, sensor, trajectory, output, object.NAME)");
	}
	if (!cfg.sectionExists("scene"))
		throw std::invalid_argument(sourceName + ": missing section [scene]");
	sc.options.loadFromConfigFile(cfg, "scene");
	if (framesOverride > 0) sc.options.frames = framesOverride;

	std::string camSpec = sc.options.camera;
	if (camSpec.size() > 4 && camSpec.substr(camSpec.size() - 4) == ".ini" && camSpec[0] != '/')
		camSpec = (std::filesystem::path(sourceName).parent_path() / camSpec).string();
	sc.camera = core::RgbdCamera::FromPresetOrFile(camSpec);
	if (cfg.sectionExists("camera")) sc.camera.loadFromConfigFile(cfg, "camera");

	if (cfg.sectionExists("sensor"))
	{
		checkKeys(
			cfg, "sensor",
			{"noise", "sigma_a", "sigma_b", "sigma_z0", "quantise_disparity", "baseline",
			 "disparity_subpixel", "min_range", "max_range", "max_incidence_deg",
			 "dropout_probability", "image_noise_sigma", "disparity_distortion", "rolling_shutter_readout"});
		sc.sensor.loadFromConfigFile(cfg, "sensor");
	}

	// Without [trajectory] the scene can only be used for augmenting real sequences.
	if (cfg.sectionExists("trajectory"))
	{
		checkKeys(cfg, "trajectory", {"loop", "ref_speed", "ref_turn_rate_deg"}, {"wp_"});
		const bool loop = ini::readBool(cfg, "trajectory", "loop", false);
		const double rate = sc.options.rateHz;
		// A loop's last frame comes one frame before the start pose; an open path ends on its
		// last waypoint.
		const double duration =
			loop ? sc.options.frames / rate
				 : std::max(1.0, static_cast<double>(sc.options.frames) - 1.0) / rate;
		sc.trajectory = CameraTrajectory::loadFromConfigFile(cfg, "trajectory", duration);
	}

	for (const auto& s : objectSections)
	{
		SceneObject obj;
		TextureOptions tex;
		loadObject(cfg, s, sc.options.seed, obj, tex);
		sc.addObject(std::move(obj), tex);
	}
	if (sc.objects.empty())
		throw std::invalid_argument(sourceName + ": the scene has no [object.NAME] section");
	return sc;
}

}  // namespace keygrid::sim
