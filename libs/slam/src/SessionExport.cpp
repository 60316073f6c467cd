#include <keygrid/core/Frame.h>
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/maps/ExportFrame.h>
#include <keygrid/core/AtomicOutput.h>
#include <keygrid/slam/MetricMaps.h>
#include <keygrid/slam/SessionExport.h>
#include <keygrid/slam/SessionLoader.h>
#include <keygrid/slam/SimpleMapExport.h>
#include <keygrid/slam/StoredKeyFrameImages.h>
#include <keygrid/slam/System.h>
#include <keygrid/store/MapSnapshotCodec.h>
#include <keygrid/store/SessionStore.h>

#include <filesystem>
#include <sstream>

namespace keygrid::slam
{
SessionExportResult exportSession(const std::string& file, const std::string& dir)
{
	std::error_code ec;
	std::filesystem::create_directories(dir, ec);
	if (ec || !std::filesystem::is_directory(dir))
		throw std::runtime_error("cannot create output folder '" + dir + "'" + (ec ? ": " + ec.message() : std::string()));
	const auto session = store::SessionStore::Open(file);
	SessionExportResult out;

	sfm::SparseMap map;
	const auto loaded = loadSparseMap(session, map);
	out.keyframes = loaded.keyframes;
	out.landmarks = loaded.landmarks;
	{
		std::ostringstream t;
		t << "# keyframes of session " << file << "\n# timestamp tx ty tz qx qy qz qw  (T_world_cam, optical frame)\n";
		for (const auto& [id, kf] : map.keyframes()) t << core::tumLine({kf.timestamp, kf.T_world_cam}) << "\n";
		core::writeFileAtomically(dir + "/keyframes.txt", t.str());
		out.files.push_back("keyframes.txt");
	}

	std::optional<mrpt::poses::CPose3D> T_world_floor;
	const auto& attrs = session.meta().attributes;
	if (const auto it = attrs.find(System::kFloorAttribute); it != attrs.end())
	{
		try
		{
			T_world_floor = maps::poseFromMatrixText(it->second);
		}
		catch (const std::invalid_argument& e)
		{
			throw std::runtime_error("'" + file + "': meta " + it->first + ": " + e.what());
		}
	}
	std::vector<mrpt::maps::CMetricMap::Ptr> maps;
	bool hocMap = false;
	for (const auto& name : session.snapshotNames())
	{
		const auto snap = session.loadSnapshot(name);
		auto m = std::dynamic_pointer_cast<mrpt::maps::CMetricMap>(store::MapSnapshotCodec::decode(*snap));
		if (!m) throw std::runtime_error("'" + file + "': snapshot '" + name + "' is not a metric map");
		hocMap = hocMap || std::dynamic_pointer_cast<CHOCPointsMap>(m) != nullptr;
		maps.push_back(m);
		out.snapshots.emplace_back(name, snap->lastKeyFrame);
	}
	for (const auto& f : MetricMaps::FromMaps(maps, T_world_floor).writeOutputs(dir)) out.files.push_back(f);
	if (!hocMap)
	{
		hocPointsFromLandmarks(map, maps::HocOptions{})
			.saveAsPly(dir + "/hoc_points.ply.tmp", T_world_floor ? maps::floorExportFrame(*T_world_floor) : maps::ExportFrame{});
		std::filesystem::rename(dir + "/hoc_points.ply.tmp", dir + "/hoc_points.ply");
		out.files.push_back("hoc_points.ply");
	}

	// The images one keyframe at a time, from the file into keyframes.simplemap.
	out.simpleMapEntries = writeKeyframesSimpleMap(map, StoredKeyFrameImages(session), dir + "/keyframes.simplemap");
	out.files.push_back("keyframes.simplemap");
	return out;
}

}  // namespace keygrid::slam
