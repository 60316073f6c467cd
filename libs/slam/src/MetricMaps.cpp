#include <keygrid/core/ConfigReading.h>
#include <keygrid/slam/IniReference.h>
#include <keygrid/slam/MetricMaps.h>
#include <keygrid/slam/SimpleMapExport.h>
#include <mrpt/math/CQuaternion.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/maps/TMetricMapTypesRegistry.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <chrono>
#include <future>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>

namespace keygrid::slam
{
core::OptionFields MapFeedOptions::fields()
{
	core::OptionFields f;
	f.add("ism2d_input", ism2dInput, "input of the 2D ISM grid: sparse (map points) | dense (depth image)", core::OptionRule::oneOf({"sparse", "dense"}));
	f.add("sparse_min_parallax_deg", sparseMinParallaxDeg, "the maps take map points without depth only when seen under rays this far apart [deg]; 0 = all", core::OptionRule::fromBelow(0, 90));
	f.add("refresh_final_points", refreshFinalPoints, "after the final refinement the maps take the map points of keyframes without depth as the refined map holds them (else as when inserted)");
	return f;
}

void MapFeedOptions::validate(const std::string& s) const { core::validateFields(*this, s); }

namespace
{
bool knownMapType(const std::string& name)
{
	for (const auto& [registered, ctors] : mrpt::maps::internal::TMetricMapTypesRegistry::Instance().getAllRegistered())
	{
		std::stringstream ss(registered);
		std::string part;
		while (std::getline(ss, part, ','))
			if (part == name) return true;
	}
	return false;
}
}  // namespace

CHOCPointsMap hocPointsFromLandmarks(const sfm::SparseMap& map, const maps::HocOptions& hoc)
{
	CHOCPointsMap m(hoc);
	const auto nb = static_cast<std::size_t>(m.geometry().numBins());
	std::vector<CHOCPointsMap::Point> pts;
	pts.reserve(map.numLandmarks());
	for (const auto& [id, lm] : map.landmarks())
	{
		CHOCPointsMap::Point p;
		p.id = id;
		p.p = {lm.p_world.x(), lm.p_world.y(), lm.p_world.z()};
		if (!lm.descriptor.empty())
		{
			const cv::Mat d = lm.descriptor.isContinuous() ? lm.descriptor : lm.descriptor.clone();
			p.descriptor.assign(d.data, d.data + d.total() * d.elemSize());
		}
		if (lm.hoc.counts().size() == nb) p.hoc = lm.hoc;
		pts.push_back(std::move(p));
	}
	m.setPoints(std::move(pts));
	return m;
}

namespace
{
/** A keygrid plugin's option section holds only keys its map definition reads (those
 * IniReference records); MRPT's own maps are left to MRPT. */
void checkPluginKeys(const mrpt::config::CConfigFileBase& cfg, const std::string& section, const std::string& type, const std::string& group)
{
	static const auto plugins = keygridMapPluginNames();
	if (std::find(plugins.begin(), plugins.end(), type) == plugins.end()) return;
	const auto reference = mapPluginReference(type);
	if (!reference) return;
	const std::string refName = std::string(MetricMaps::kSection) + "_" + type + "_00_" + group;
	const auto ref = std::find_if(reference->begin(), reference->end(), [&](const IniSection& r) { return r.name == refName; });
	if (ref == reference->end())
		throw std::invalid_argument("[" + section + "]: map type '" + type + "' reads no " + group + " (doc/ini-reference.md)");
	std::vector<std::string> keys;
	cfg.getAllKeys(section, keys);
	for (const auto& k : keys)
		if (std::none_of(ref->keys.begin(), ref->keys.end(), [&](const IniKey& r) { return r.key == k; }))
			throw std::invalid_argument("[" + section + "] " + k + ": unknown key (typo? doc/ini-reference.md lists the keys of " + type + ")");
}

/** Every [MappingApplication_<type>_<NN>_<group>] section names a map type that is
 * configured or registered and an option group MRPT's maps read; a misspelt one would be
 * ignored with all its keys. */
void checkMapSections(const mrpt::config::CConfigFileBase& cfg, const std::map<std::string, int>& counts)
{
	static const std::regex pattern(std::string(MetricMaps::kSection) + "_(.+)_([0-9]+)_([A-Za-z]+)");
	static const std::set<std::string> groups = {"creationOpts", "insertOpts", "likelihoodOpts", "renderOpts", "colorOpts"};
	const std::string prefix = std::string(MetricMaps::kSection) + "_";
	std::vector<std::string> sections;
	cfg.getAllSections(sections);
	for (const auto& name : sections)
	{
		if (name.compare(0, prefix.size(), prefix) != 0) continue;
		std::smatch m;
		if (!std::regex_match(name, m, pattern))
			throw std::invalid_argument("[" + name + "]: not a map option section (expected " + prefix + "<type>_<NN>_<group>)");
		// A map switched off (<type>_count = 0, or fewer maps than sections) keeps its options;
		// a type that is neither configured nor registered is a typo.
		if (!counts.count(m[1].str()) && !knownMapType(m[1].str()))
			throw std::invalid_argument(
				"[" + name + "]: no map type '" + m[1].str() + "' is configured in [" + MetricMaps::kSection +
				"] or registered (typo?)");
		if (!groups.count(m[3].str()))
			throw std::invalid_argument(
				"[" + name + "]: unknown option group '" + m[3].str() + "' (creationOpts, insertOpts, likelihoodOpts, renderOpts, colorOpts)");
		checkPluginKeys(cfg, name, m[1].str(), m[3].str());
	}
}
}  // namespace

MetricMaps::MetricMaps(
	const mrpt::config::CConfigFileBase& cfg, const MapFeedOptions& feed, const maps::FloorFrameOptions& floor)
	: m_feed(feed), m_floor(floor)
{
	if (!cfg.sectionExists(kSection)) return;
	std::vector<std::string> keys;
	cfg.getAllKeys(kSection, keys);
	std::size_t requested = 0;
	std::map<std::string, int> counts;
	for (const auto& k : keys)
	{
		if (k.size() < 7 || k.substr(k.size() - 6) != "_count") continue;
		const std::string name = k.substr(0, k.size() - 6);
		const int n = static_cast<int>(core::readInteger(cfg, kSection, k, 0, 0, 16));
		counts[name] = n;
		if (n > 0 && !knownMapType(name))
			throw std::invalid_argument(
				std::string("[") + kSection + "] " + k + ": no map type '" + name +
				"' is registered (typo, or its plugin library is not loaded)");
		requested += static_cast<std::size_t>(n);
	}
	checkMapSections(cfg, counts);
	mrpt::maps::TSetOfMetricMapInitializers init;
	init.loadFromConfigFile(cfg, kSection);
	m_maps.setListOfMaps(init);
	if (m_maps.maps.size() != requested)
		throw std::invalid_argument(
			std::string("[") + kSection + "] asks for " + std::to_string(requested) + " maps but " +
			std::to_string(m_maps.maps.size()) + " were created");
	listKeyFrameMaps();
	// Every map takes the run's floor frame (a 2D grid refuses one of its own).
	for (auto* m : m_keyFrameMaps) m->setFloorFrame(m_floor.T_world_floor());
}

void MetricMaps::listKeyFrameMaps()
{
	m_keyFrameMaps.clear();
	m_observationFedMaps.clear();
	for (auto& m : m_maps.maps)
		if (auto* km = dynamic_cast<maps::KeyFrameMap*>(m.get()))
			m_keyFrameMaps.push_back(km);
		else
			m_keyFrameMaps.push_back(m_observationFedMaps.emplace_back(std::make_unique<maps::ObservationFedMap>(*m)).get());
}

maps::ExportFrame MetricMaps::outputFrame() const
{
	if (m_restoredFloor) return maps::floorExportFrame(*m_restoredFloor);
	if (T_world_floor()) return maps::floorExportFrame(*T_world_floor());
	return {mrpt::poses::CPose3D(), "keygrid frame: SLAM world (the first camera's optical frame; no floor estimate)"};
}

maps::MapKeyFrame MetricMaps::mapKeyFrame(const sfm::SparseMap& map, sfm::KeyFrameId id, double travelled) const
{
	const auto& kf = map.keyframe(id);
	maps::MapKeyFrame out;
	out.id = id;
	out.T_world_cam = kf.T_world_cam;
	out.camera = kf.features.camera;
	out.depth = depthOf(kf);
	out.points_world = mapPointsOf(map, id);
	out.travelled = travelled;
	return out;
}

std::vector<mrpt::math::TPoint3D> MetricMaps::mapPointsOf(const sfm::SparseMap& map, sfm::KeyFrameId id) const
{
	const auto& kf = map.keyframe(id);
	std::vector<mrpt::math::TPoint3D> out;
	const double minCos = std::cos(m_feed.sparseMinParallaxDeg * M_PI / 180.0);
	for (std::size_t i = 0; i < kf.landmarks.size(); i++)
	{
		const sfm::LandmarkId l = kf.landmarks[i];
		if (l == sfm::kNoLandmark || !map.hasLandmark(l)) continue;
		const auto& lm = map.landmark(l);
		const bool hasDepth = i < kf.features.depth.size() && kf.features.depth[i] > 0;
		if (m_feed.sparseMinParallaxDeg > 0 && !hasDepth && !(sfm::largestParallaxCos(map, lm) <= minCos)) continue;
		out.emplace_back(lm.p_world.x(), lm.p_world.y(), lm.p_world.z());
	}
	return out;
}

std::map<sfm::KeyFrameId, std::vector<mrpt::math::TPoint3D>> MetricMaps::refreshedMapPoints(const sfm::SparseMap& map) const
{
	std::map<sfm::KeyFrameId, std::vector<mrpt::math::TPoint3D>> out;
	if (!m_feed.refreshFinalPoints || empty()) return out;
	for (const auto& [id, T] : m_insertedPoses)
	{
		if (!map.hasKeyFrame(id)) continue;
		const auto& depth = map.keyframe(id).features.depth;
		if (std::any_of(depth.begin(), depth.end(), [](float d) { return d > 0; })) continue;
		out[id] = mapPointsOf(map, id);
	}
	return out;
}

void MetricMaps::insertKeyFrame(const sfm::SparseMap& map, sfm::KeyFrameId id, double travelled)
{
	if (empty()) return;
	const maps::MapKeyFrame kf = mapKeyFrame(map, id, travelled);
	m_insertedPoses[id] = kf.T_world_cam;
	m_travelled[id] = travelled;
	// The floor first, so that the keyframe enters the 2D grids in the newest floor frame.
	// Samples of its depth image, else its map points.
	if (!m_floor.given() && !m_floorFromHeight)
	{
		std::vector<mrpt::math::TPoint3Df> samples;
		if (!kf.depth.empty())
		{
			const cv::Mat d = kf.depth.isContinuous() ? kf.depth : kf.depth.clone();
			const auto& cam = kf.camera;
			samples = maps::FloorFrameEstimator::depthSamples(d.ptr<float>(), d.rows, d.cols, cam.fx, cam.fy, cam.cx, cam.cy, m_floor.options());
		}
		else
			for (const auto& p : kf.points_world)
			{
				const auto q = kf.T_world_cam.inverseComposePoint(p);
				samples.emplace_back(static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(q.z));
			}
		if (m_floor.addKeyframe(id, kf.T_world_cam, samples, map.keyframe(id).timestamp))
			for (auto* m : m_keyFrameMaps) m->setFloorFrame(m_floor.T_world_floor());
	}
	maps::KeyFrameFeed feed;
	feed.gridInput = m_feed.ism2dInput == "dense" ? maps::GridInput::Depth : maps::GridInput::MapPoints;
	feed.keyFrame = [&](uint64_t earlier) -> std::optional<maps::MapKeyFrame> {
		if (!map.hasKeyFrame(earlier)) return std::nullopt;
		const auto t = m_travelled.find(earlier);
		return mapKeyFrame(map, earlier, t != m_travelled.end() ? t->second : 0.0);
	};
	for (auto* m : m_keyFrameMaps) m->insertKeyFrame(kf, feed);
}

cv::Mat MetricMaps::depthOf(const sfm::KeyFrame& kf) const
{
	if (!kf.depth.empty() || !m_images) return kf.depth;
	return m_images->load(kf).depth;
}

std::map<std::string, double> MetricMaps::applyCorrection(
	const std::map<sfm::KeyFrameId, mrpt::poses::CPose3D>& newPoses, const std::map<sfm::KeyFrameId, double>& newScales,
	const std::map<sfm::KeyFrameId, std::vector<mrpt::math::TPoint3D>>& newPoints)
{
	for (const auto& [id, s] : newScales)
		if (!(s > 0) || !std::isfinite(s))
			throw std::invalid_argument("MetricMaps::applyCorrection: keyframe " + std::to_string(id) + " scale " +
										std::to_string(s) + " is not a positive finite factor");
	const auto scaleOf = [&](sfm::KeyFrameId id) {
		const auto it = newScales.find(id);
		return it != newScales.end() ? it->second : 1.0;
	};
	std::map<std::string, double> out;
	maps::MapCorrection correction;
	{
		// The floor under the corrected poses. The maps are re-anchored below anyway, so they
		// take the newest floor frame even when it did not change now (a 2D grid may have kept
		// an older one, see floorReanchorShift).
		const auto t0 = std::chrono::steady_clock::now();
		std::map<uint64_t, mrpt::poses::CPose3D> np(newPoses.begin(), newPoses.end());
		if (!m_floorFromHeight) m_floor.updatePoses(np, newScales);
		correction.T_world_floor = T_world_floor();
		out["floor"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	}
	for (const auto& [id, T] : newPoses)
		if (m_insertedPoses.count(id)) correction.poses[id] = PoseCorrection{m_insertedPoses.at(id), T, scaleOf(id)};
	for (const auto& [id, pts] : newPoints)
		if (m_insertedPoses.count(id)) correction.points_world[id] = pts;
	for (const auto& [name, sec] : dispatchCorrection(correction)) out[name] = sec;
	for (const auto& [id, T] : newPoses)
		if (m_insertedPoses.count(id)) m_insertedPoses[id] = T;
	return out;
}

void MetricMaps::useFloorFromCameraHeight()
{
	if (!m_insertedPoses.empty())
		throw std::logic_error("MetricMaps::useFloorFromCameraHeight: called after keyframes were inserted");
	m_floorFromHeight = true;
}

std::map<std::string, double> MetricMaps::applyRescale(
	const sfm::SparseMap& map, double s, const Eigen::Vector3d& n_floor, double d_floor)
{
	if (!(s > 0) || !std::isfinite(s))
		throw std::invalid_argument("MetricMaps::applyRescale: scale " + std::to_string(s) + " is not a positive finite factor");
	std::map<std::string, double> out;
	if (empty()) return out;
	maps::MapCorrection correction;
	correction.scale = s;
	for (auto& [id, T_old] : m_insertedPoses)
	{
		mrpt::poses::CPose3D T_new;
		if (!map.poseOf(id, T_new))
		{
			T_new = T_old;  // not in the map any more: it follows the scale only
			sfm::scaleTranslation(T_new, s);
		}
		correction.poses[id] = PoseCorrection{T_old, T_new};
		T_old = T_new;
	}
	for (auto& [id, t] : m_travelled) t *= s;
	setFloorFromCameraHeight(n_floor, d_floor);
	correction.T_world_floor = T_world_floor();
	return dispatchCorrection(correction);
}

void MetricMaps::setFloorFromCameraHeight(const Eigen::Vector3d& n_floor, double d_floor)
{
	if (!m_floorFromHeight || m_insertedPoses.empty()) return;
	// The frame's origin and heading: the first keyframe's footprint and view direction.
	const auto& first = m_insertedPoses.begin()->second;
	maps::FloorPlane plane;
	plane.normal = mrpt::math::TVector3D(n_floor.x(), n_floor.y(), n_floor.z());
	plane.d = d_floor;
	m_heightFloor = maps::floorPoseFromPlane(plane, first.translation(), first.rotateVector(mrpt::math::TVector3D(0, 0, 1)));
}

std::string MetricMaps::floorJson() const
{
	if (!m_floorFromHeight) return m_floor.toJson();
	std::ostringstream o;
	o << "{\"source\": \"camera_height\", \"T_world_floor\": ";
	if (m_heightFloor)
	{
		mrpt::math::CQuaternionDouble q;
		m_heightFloor->getAsQuaternion(q);
		char b[256];
		std::snprintf(b, sizeof(b), "[%.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g]", m_heightFloor->x(), m_heightFloor->y(),
					  m_heightFloor->z(), q.x(), q.y(), q.z(), q.r());
		o << b;
	}
	else
		o << "null";
	o << "}";
	return o.str();
}

std::map<std::string, double> MetricMaps::dispatchCorrection(const maps::MapCorrection& correction)
{
	std::map<std::string, double> out;
	// The maps are independent of each other: all but the first are re-anchored on threads of
	// their own (the result does not depend on the order).
	std::vector<double> seconds(m_keyFrameMaps.size(), -1.0);
	const auto correct = [&](std::size_t i)
	{
		const auto t0 = std::chrono::steady_clock::now();
		if (m_keyFrameMaps[i]->applyCorrection(correction))
			seconds[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	};
	std::vector<std::future<void>> others;
	for (std::size_t i = 1; i < m_keyFrameMaps.size(); i++) others.push_back(std::async(std::launch::async, correct, i));
	if (!m_keyFrameMaps.empty()) correct(0);
	for (auto& f : others) f.get();
	for (std::size_t i = 0; i < seconds.size(); i++)
		if (seconds[i] >= 0) out[m_maps.maps[i]->GetRuntimeClass()->className] = seconds[i];
	return out;
}

void MetricMaps::syncLandmarks(const sfm::SparseMap& map, const maps::HocOptions& hoc)
{
	const maps::LandmarkSource landmarks = [&] { return hocPointsFromLandmarks(map, hoc); };
	for (auto* m : m_keyFrameMaps) m->syncLandmarks(landmarks);
}

void MetricMaps::notifyLoopClosure()
{
	for (auto* m : m_keyFrameMaps) m->notifyLoopClosure();
}

MetricMaps MetricMaps::FromMaps(
	const std::vector<mrpt::maps::CMetricMap::Ptr>& maps, const std::optional<mrpt::poses::CPose3D>& T_world_floor)
{
	MetricMaps out(MapFeedOptions{}, maps::FloorFrameOptions{});
	out.m_restoredFloor = T_world_floor;
	for (const auto& m : maps) out.m_maps.maps.push_back(m);
	out.listKeyFrameMaps();
	return out;
}

std::vector<std::string> MetricMaps::writeOutputs(const std::string& dir) const
{
	maps::MapOutputFolder out(dir, outputFrame());
	std::map<std::string, int> seen;
	for (std::size_t i = 0; i < m_keyFrameMaps.size(); i++)
	{
		const int n = seen[m_maps.maps[i]->GetRuntimeClass()->className]++;
		m_keyFrameMaps[i]->writeOutputs(out, n ? "_" + std::to_string(n) : "");
	}
	out.throwIfAnyFailed();
	return out.files();
}

std::string MetricMaps::summaryJson() const
{
	std::ostringstream o;
	o << "[";
	for (std::size_t i = 0; i < m_keyFrameMaps.size(); i++)
	{
		o << (i ? ", " : "") << "{\"class\": \"" << m_maps.maps[i]->GetRuntimeClass()->className << "\"";
		const std::string fields = m_keyFrameMaps[i]->summaryJsonFields();
		if (!fields.empty()) o << ", " << fields;
		o << "}";
	}
	o << "]";
	return o.str();
}

}  // namespace keygrid::slam
