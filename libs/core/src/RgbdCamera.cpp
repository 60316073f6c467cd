#include <keygrid/core/ConfigReading.h>
#include <keygrid/core/RgbdCamera.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/system/filesystem.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace keygrid::core
{
namespace
{
RgbdCamera make(
	const char* name, double fx, double fy, double cx, double cy, std::array<double, 5> d)
{
	RgbdCamera c;
	c.name = name;
	c.fx = fx;
	c.fy = fy;
	c.cx = cx;
	c.cy = cy;
	c.dist = d;
	return c;
}
}  // namespace

bool RgbdCamera::hasDistortion() const
{
	for (double d : dist)
		if (d != 0.0) return true;
	return false;
}

RgbdCamera RgbdCamera::Preset(const std::string& n)
{
	// Calibrations published with TUM RGB-D (vision.in.tum.de "file formats") and ICL-NUIM.
	if (n == "kinect") return make("kinect", 525.0, 525.0, 319.5, 239.5, {0, 0, 0, 0, 0});
	if (n == "fr1")
		return make(
			"fr1", 517.306408, 516.469215, 318.643040, 255.313989,
			{0.262383, -0.953104, -0.005358, 0.002628, 1.163314});
	if (n == "fr2")
		return make(
			"fr2", 520.908620, 521.007327, 325.141442, 249.701764,
			{0.231222, -0.784899, -0.003257, -0.000105, 0.917205});
	if (n == "fr3") return make("fr3", 535.4, 539.2, 320.1, 247.6, {0, 0, 0, 0, 0});
	if (n == "icl") return make("icl", 481.20, -480.00, 319.50, 239.50, {0, 0, 0, 0, 0});
	throw std::invalid_argument(
		"unknown camera preset '" + n + "' (expected kinect, fr1, fr2, fr3, icl or an INI file)");
}

void RgbdCamera::loadFromConfigFile(
	const mrpt::config::CConfigFileBase& cfg, const std::string& s)
{
	auto num = [&](const char* key, double cur) { return readFiniteNumber(cfg, s, key, cur); };
	name = cfg.read_string(s, "name", name, false);
	fx = num("fx", fx);
	fy = num("fy", fy);
	cx = num("cx", cx);
	cy = num("cy", cy);
	width = static_cast<unsigned int>(num("width", width));
	height = static_cast<unsigned int>(num("height", height));
	const char* dk[5] = {"k1", "k2", "p1", "p2", "k3"};
	for (int i = 0; i < 5; i++) dist[i] = num(dk[i], dist[i]);
	depthUnits = static_cast<float>(num("depth_units", depthUnits));
	std::string err;
	if (!isValid(&err)) throw std::invalid_argument("[" + s + "] " + err);
}

void RgbdCamera::saveToConfigFile(
	mrpt::config::CConfigFileBase& cfg, const std::string& s) const
{
	cfg.write(s, "name", name);
	cfg.write(s, "width", width);
	cfg.write(s, "height", height);
	cfg.write(s, "fx", fx);
	cfg.write(s, "fy", fy);
	cfg.write(s, "cx", cx);
	cfg.write(s, "cy", cy);
	const char* dk[5] = {"k1", "k2", "p1", "p2", "k3"};
	for (int i = 0; i < 5; i++) cfg.write(s, dk[i], dist[i]);
	cfg.write(s, "depth_units", depthUnits);
}

RgbdCamera RgbdCamera::FromPresetOrFile(const std::string& v)
{
	if (v.size() > 4 && v.substr(v.size() - 4) == ".ini")
	{
		if (!mrpt::system::fileExists(v))
			throw std::invalid_argument("camera file '" + v + "' does not exist");
		mrpt::config::CConfigFile cfg(v);
		if (!cfg.sectionExists("camera"))
			throw std::invalid_argument("camera file '" + v + "' has no [camera] section");
		RgbdCamera c;
		c.name = mrpt::system::extractFileName(v);
		c.loadFromConfigFile(cfg, "camera");
		return c;
	}
	return Preset(v);
}

bool RgbdCamera::isValid(std::string* error) const
{
	std::ostringstream e;
	if (width == 0 || height == 0) e << "width/height must be > 0 (got " << width << "x" << height << ")";
	else if (!(fx != 0 && fy != 0 && std::isfinite(fx) && std::isfinite(fy)))
		e << "fx, fy must be finite and non-zero (got " << fx << ", " << fy << ")";
	else if (!(std::isfinite(cx) && std::isfinite(cy)))
		e << "cx, cy must be finite";
	else if (!(depthUnits > 0 && std::isfinite(depthUnits)))
		e << "depth_units must be > 0 (got " << depthUnits << ")";
	if (error) *error = e.str();
	return e.str().empty();
}

mrpt::img::TCamera RgbdCamera::toTCamera() const
{
	mrpt::img::TCamera c;
	c.ncols = width;
	c.nrows = height;
	c.setIntrinsicParamsFromValues(fx, fy, cx, cy);
	if (hasDistortion())
		c.setDistortionPlumbBob(dist[0], dist[1], dist[2], dist[3], dist[4]);
	else
		c.distortion = mrpt::img::DistortionModel::none;
	c.cameraName = name;
	return c;
}

RgbdCamera RgbdCamera::FromTCamera(const mrpt::img::TCamera& t, float units)
{
	RgbdCamera c;
	c.name = t.cameraName;
	c.width = t.ncols;
	c.height = t.nrows;
	c.fx = t.fx();
	c.fy = t.fy();
	c.cx = t.cx();
	c.cy = t.cy();
	if (t.distortion == mrpt::img::DistortionModel::plumb_bob)
		c.dist = {t.k1(), t.k2(), t.p1(), t.p2(), t.k3()};
	c.depthUnits = units;
	return c;
}

}  // namespace keygrid::core
