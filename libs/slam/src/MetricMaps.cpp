#include <keygrid/core/AtomicOutput.h>
#include <keygrid/core/ConfigReading.h>
#include <keygrid/core/FrameConventions.h>
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <keygrid/slam/IniReference.h>
#include <keygrid/slam/MetricMaps.h>
#include <keygrid/slam/SimpleMapExport.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/maps/TMetricMapTypesRegistry.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>

namespace keygrid::slam
{
void MapFeedOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	ism2dInput = c.read_string(s, "ism2d_input", ism2dInput);
	if (ism2dInput != "sparse" && ism2dInput != "dense")
		throw std::invalid_argument("[" + s + "] ism2d_input = '" + ism2dInput + "' (expected sparse or dense)");
}

void MapFeedOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	c.write(s, "ism2d_input", ism2dInput, 30, 40, "sparse (map points) | dense (depth image)");
}

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

/** A depth-only observation of a keyframe, for MRPT's own maps. */
mrpt::obs::CObservation3DRangeScan::Ptr depthObservation(const sfm::KeyFrame& kf, const cv::Mat& depth)
{
	auto obs = mrpt::obs::CObservation3DRangeScan::Create();
	const auto& cam = kf.features.camera;
	obs->hasRangeImage = true;
	obs->range_is_depth = true;
	obs->rangeUnits = cam.depthUnits;
	obs->rangeImage.resize(depth.rows, depth.cols);
	for (int r = 0; r < depth.rows; r++)
		for (int c = 0; c < depth.cols; c++)
		{
			const double q = std::round(depth.at<float>(r, c) / cam.depthUnits);
			obs->rangeImage(r, c) = q > 0 && q < 65535 ? static_cast<uint16_t>(q) : 0;
		}
	obs->cameraParams = cam.toTCamera();
	obs->cameraParamsIntensity = obs->cameraParams;
	obs->relativePoseIntensityWRTDepth = core::T_depth_cam();
	obs->maxRange = 10.0f;
	return obs;
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
	// Every 2D grid takes the run's floor frame. A grid's own floor pose would be silently
	// replaced: refuse it, naming where the floor of a keygrid-slam run is given.
	for (std::size_t i = 0; i < m_maps.maps.size(); i++)
		if (auto* ism = dynamic_cast<CISMOccupancyGrid2D*>(m_maps.maps[i].get()))
		{
			const auto& io = ism->insertionOptions;
			if (!io.estimateFloorFromDepth && !maps::ExportFrame{io.T_world_floor, {}}.isIdentity())
				throw std::invalid_argument(
					std::string("[") + kSection + "_ismOccupancyGrid2D_" + (i < 10 ? "0" : "") + std::to_string(i) +
					"_insertOpts] T_world_floor: keygrid-slam gives every map the run's one floor frame; set it as "
					"[floor] T_world_floor instead");
			if (m_floor.T_world_floor())
				ism->setExternalFloorPose(*m_floor.T_world_floor());
			else
				ism->expectExternalFloorPose();
		}
}

void MetricMaps::floorChanged()
{
	for (auto& m : m_maps.maps)
		if (auto* ism = dynamic_cast<CISMOccupancyGrid2D*>(m.get()))
		{
			ism->setExternalFloorPose(*m_floor.T_world_floor());
			// The keyframes integrated so far, again in the new floor frame (cheap).
			if (!ism->keyframes().empty()) ism->applyTrajectoryCorrection({});
		}
}

maps::ExportFrame MetricMaps::outputFrame() const
{
	if (m_restoredFloor) return maps::floorExportFrame(*m_restoredFloor);
	if (m_floor.T_world_floor()) return maps::floorExportFrame(*m_floor.T_world_floor());
	return {mrpt::poses::CPose3D(), "keygrid frame: SLAM world (the first camera's optical frame; no floor estimate)"};
}

void MetricMaps::insertKeyFrame(const sfm::SparseMap& map, sfm::KeyFrameId id, double travelled)
{
	if (empty()) return;
	const auto& kf = map.keyframe(id);
	const cv::Mat depth = depthOf(kf);
	m_insertedPoses[id] = kf.T_world_cam;
	// The floor first, so that the keyframe enters the 2D grids in the newest floor frame.
	// Samples of its depth image, else its map points.
	if (!m_floor.given())
	{
		std::vector<mrpt::math::TPoint3Df> samples;
		if (!depth.empty())
		{
			const cv::Mat d = depth.isContinuous() ? depth : depth.clone();
			const auto& cam = kf.features.camera;
			samples = maps::FloorFrameEstimator::depthSamples(d.ptr<float>(), d.rows, d.cols, cam.fx, cam.fy, cam.cx, cam.cy, m_floor.options());
		}
		else
			for (sfm::LandmarkId l : kf.landmarks)
				if (l != sfm::kNoLandmark && map.hasLandmark(l))
				{
					const auto& p = map.landmark(l).p_world;
					const auto q = kf.T_world_cam.inverseComposePoint(mrpt::math::TPoint3D(p.x(), p.y(), p.z()));
					samples.emplace_back(static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(q.z));
				}
		if (m_floor.addKeyframe(id, kf.T_world_cam, samples, kf.timestamp)) floorChanged();
	}
	mrpt::obs::CObservation3DRangeScan::Ptr obs;  // built on demand
	for (std::size_t i = 0; i < m_maps.maps.size(); i++)
	{
		auto& m = m_maps.maps[i];
		if (auto* ism = dynamic_cast<CISMOccupancyGrid2D*>(m.get()))
		{
			if (m_feed.ism2dInput == "dense" && !depth.empty())
			{
				// Dense input is reduced in the floor frame: it waits for the floor.
				auto& pending = m_pendingDense[i];
				if (!ism->floorKnown())
				{
					pending.push_back(id);
					continue;
				}
				for (sfm::KeyFrameId p : pending)
					if (map.hasKeyFrame(p))
					{
						const auto& pk = map.keyframe(p);
						ism->insertKeyframeDepth(p, pk.T_world_cam, *depthObservation(pk, depthOf(pk)));
					}
				pending.clear();
				if (!obs) obs = depthObservation(kf, depth);
				ism->insertKeyframeDepth(id, kf.T_world_cam, *obs);
				continue;
			}
			// Sparse input is stored also before the floor is known, and integrated then.
			std::vector<mrpt::math::TPoint3D> pts;
			for (sfm::LandmarkId l : kf.landmarks)
				if (l != sfm::kNoLandmark && map.hasLandmark(l))
				{
					const auto& p = map.landmark(l).p_world;
					pts.emplace_back(p.x(), p.y(), p.z());
				}
			ism->insertKeyframePoints(id, kf.T_world_cam, pts);
		}
		else if (auto* g3 = dynamic_cast<CSubmappedOccupancyGrid3D*>(m.get()))
		{
			if (!depth.empty()) g3->insertDepthFrame(depth, kf.features.camera, kf.T_world_cam, travelled, id);
		}
		else if (dynamic_cast<CHOCPointsMap*>(m.get()))
			continue;  // filled from the frontend's landmarks (syncLandmarks)
		else if (!depth.empty())
		{
			if (!obs) obs = depthObservation(kf, depth);
			m->insertObservation(*obs, mrpt::poses::CPose3D(core::sensorPoseFromCameraPose(kf.T_world_cam)));
		}
	}
}

cv::Mat MetricMaps::depthOf(const sfm::KeyFrame& kf) const
{
	if (!kf.depth.empty() || !m_images) return kf.depth;
	return m_images->load(kf).depth;
}

std::map<std::string, double> MetricMaps::applyCorrection(const std::map<sfm::KeyFrameId, mrpt::poses::CPose3D>& newPoses)
{
	std::map<std::string, double> out;
	{
		// The floor under the corrected poses; the 2D grids are rebuilt below anyway.
		const auto t0 = std::chrono::steady_clock::now();
		std::map<uint64_t, mrpt::poses::CPose3D> np(newPoses.begin(), newPoses.end());
		if (m_floor.updatePoses(np))
			for (auto& m : m_maps.maps)
				if (auto* ism = dynamic_cast<CISMOccupancyGrid2D*>(m.get())) ism->setExternalFloorPose(*m_floor.T_world_floor());
		out["floor"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	}
	for (auto& m : m_maps.maps)
	{
		const auto t0 = std::chrono::steady_clock::now();
		std::string name = m->GetRuntimeClass()->className;
		if (auto* ism = dynamic_cast<CISMOccupancyGrid2D*>(m.get()))
		{
			if (!ism->floorKnown()) continue;  // nothing integrated yet: no floor frame
			std::map<uint64_t, mrpt::poses::CPose3D> np;
			for (const auto& [id, T] : newPoses)
				if (ism->keyframes().count(id)) np[id] = T;
			ism->applyTrajectoryCorrection(np);
		}
		else if (auto* g3 = dynamic_cast<CSubmappedOccupancyGrid3D*>(m.get()))
		{
			TrajectoryCorrection corr;
			for (const auto& [id, T] : newPoses)
				if (m_insertedPoses.count(id)) corr[id] = PoseCorrection{m_insertedPoses.at(id), T};
			g3->morphAndMergeSubmaps(corr);
		}
		else
			continue;  // MRPT's own maps cannot be re-anchored: they keep the online poses
		out[name] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	}
	for (const auto& [id, T] : newPoses)
		if (m_insertedPoses.count(id)) m_insertedPoses[id] = T;
	return out;
}

void MetricMaps::syncLandmarks(const sfm::SparseMap& map, const maps::HocOptions& hoc)
{
	for (auto& m : m_maps.maps)
		if (auto* h = dynamic_cast<CHOCPointsMap*>(m.get()))
		{
			const auto render = h->renderOptions;
			const auto ins = h->insertionOptions;
			const auto lik = h->likelihoodOptions;
			*h = hocPointsFromLandmarks(map, hoc);
			h->renderOptions = render;
			h->insertionOptions = ins;
			h->likelihoodOptions = lik;
		}
}

void MetricMaps::notifyLoopClosure()
{
	for (auto& m : m_maps.maps)
		if (auto* g3 = dynamic_cast<CSubmappedOccupancyGrid3D*>(m.get())) g3->notifyLoopClosure();
}

MetricMaps MetricMaps::FromMaps(
	const std::vector<mrpt::maps::CMetricMap::Ptr>& maps, const std::optional<mrpt::poses::CPose3D>& T_world_floor)
{
	MetricMaps out(MapFeedOptions{}, maps::FloorFrameOptions{});
	out.m_restoredFloor = T_world_floor;
	for (const auto& m : maps) out.m_maps.maps.push_back(m);
	return out;
}

std::vector<std::string> MetricMaps::writeOutputs(const std::string& dir) const
{
	namespace fs = std::filesystem;
	const maps::ExportFrame frame = outputFrame();
	std::vector<std::string> files;
	std::map<std::string, int> seen;
	// Every file is tried: one that fails (full disk) does not keep the others from being
	// written. The first failure is thrown at the end.
	std::string firstError;
	std::size_t failures = 0;
	auto attempt = [&](const std::string& file, const std::function<void(const std::string&)>& write) {
		try
		{
			write(dir + "/" + file);
			files.push_back(file);
			return true;
		}
		catch (const std::exception& e)
		{
			if (firstError.empty()) firstError = e.what();
			failures++;
			return false;
		}
	};
	for (const auto& m : m_maps.maps)
	{
		const std::string cls = m->GetRuntimeClass()->className;
		const int n = seen[cls]++;
		const std::string suffix = n ? "_" + std::to_string(n) : "";
		// keygrid's maps write each file atomically (core/AtomicOutput.h).
		if (const auto* ism = dynamic_cast<const CISMOccupancyGrid2D*>(m.get()))
		{
			if (attempt("map_2d" + suffix + ".yaml", [&](const std::string& p) { ism->saveAsRosMapServer(p); }))
				files.push_back("map_2d" + suffix + ".pgm");  // written first, beside the .yaml
			attempt("map_2d" + suffix + ".png", [&](const std::string& p) { ism->saveAsImage(p); });
			attempt("map_2d" + suffix + ".bin", [&](const std::string& p) { core::saveGzAtomically(*ism, p); });
		}
		else if (const auto* g3 = dynamic_cast<const CSubmappedOccupancyGrid3D*>(m.get()))
		{
			attempt("map_3d" + suffix + ".bt", [&](const std::string& p) { g3->saveAsOctomapBinary(p, frame); });
			attempt("map_3d" + suffix + ".ply", [&](const std::string& p) { g3->saveOccupiedAsPly(p, frame); });
			attempt("map_3d" + suffix + ".bin", [&](const std::string& p) { core::saveGzAtomically(*g3, p); });
		}
		else if (const auto* hoc = dynamic_cast<const CHOCPointsMap*>(m.get()))
		{
			attempt("hoc_points" + suffix + ".ply", [&](const std::string& p) { hoc->saveAsPly(p, frame); });
			attempt("hoc_points" + suffix + ".bin", [&](const std::string& p) { core::saveGzAtomically(*hoc, p); });
		}
		else
		{
			// MRPT's own representation (e.g. octoMap writes .bt, pointsMap .txt), by writers that
			// take a file prefix: written into a scratch folder, then renamed into place.
			std::string base = cls;
			for (auto& ch : base)
				if (ch == ':') ch = '_';
			attempt(base + suffix + ".*", [&](const std::string&) {
				const fs::path tmp = fs::path(dir) / ".maps.tmp";
				fs::remove_all(tmp);
				fs::create_directories(tmp);
				m->saveMetricMapRepresentationToFile((tmp / (base + suffix)).string());
				for (const auto& e : fs::directory_iterator(tmp)) fs::rename(e.path(), fs::path(dir) / e.path().filename());
				fs::remove_all(tmp);
			});
		}
	}
	if (failures > 1) firstError += " (and " + std::to_string(failures - 1) + " more map files not written)";
	if (!firstError.empty()) throw std::runtime_error(firstError);
	return files;
}

std::string MetricMaps::summaryJson() const
{
	std::ostringstream o;
	o << "[";
	bool first = true;
	for (const auto& m : m_maps.maps)
	{
		o << (first ? "" : ", ") << "{\"class\": \"" << m->GetRuntimeClass()->className << "\"";
		if (const auto* ism = dynamic_cast<const CISMOccupancyGrid2D*>(m.get()))
		{
			const auto c = ism->countStates();
			o << ", \"cells\": " << ism->sizeX() * ism->sizeY() << ", \"states\": [" << c[0] << ", " << c[1] << ", " << c[2]
			  << "], \"keyframes\": " << ism->keyframes().size();
		}
		else if (const auto* hoc = dynamic_cast<const CHOCPointsMap*>(m.get()))
			o << ", \"points\": " << hoc->size();
		else if (const auto* g3 = dynamic_cast<const CSubmappedOccupancyGrid3D*>(m.get()))
			o << ", \"submaps\": " << g3->numSubmaps() << ", \"memory_bytes\": " << g3->memoryBytes()
			  << ", \"keyframes\": " << g3->keyframes().size();
		o << "}";
		first = false;
	}
	o << "]";
	return o.str();
}

}  // namespace keygrid::slam
