#include <keygrid/core/JsonNumber.h>
#include <keygrid/sim/GroundTruthOccupancy.h>
#include <keygrid/sim/SequenceWriter.h>
#include <keygrid/slam/apps/KeyFrameViews.h>
#include <keygrid/slam/apps/MapEvaluation.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/system/filesystem.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace keygrid::slam
{
namespace
{
maps::FloorPlanGrid toFloorPlanGrid(const sim::FloorPlan& fp)
{
	return maps::FloorPlanGrid::fromOccupancy(fp.resolution, fp.origin.x(), fp.origin.y(), fp.width, fp.height, fp.occupied);
}

/** Renders the scene at the keyframes' ground-truth poses into gt.seen; returns how many. */
std::size_t markVisibility(maps::FloorPlanGrid& gt, const MapEvaluationOptions& o, const core::Trajectory& gtTraj)
{
	if (!mrpt::system::fileExists(o.scenePath)) throw std::runtime_error("scene file '" + o.scenePath + "' does not exist");
	maps::FloorPlanVisibilityOptions vis = o.visibility;
	{
		const mrpt::config::CConfigFileMemory cfg(mrpt::io::file_get_contents(o.scenePath));
		sim::OutputOptions out;
		if (cfg.sectionExists("output")) out.loadFromConfigFile(cfg, "output");
		vis.zMin = out.floorPlanZMin;
		vis.zMax = out.floorPlanZMax;
	}
	KeyFrameViewsOptions views;
	views.scenePath = o.scenePath;
	views.keyframesPath = o.keyframesPath;
	views.maxDt = o.maxDt;
	views.progress = o.progress;
	return renderKeyFrameViews(views, gtTraj, [&](const cv::Mat& depth, const core::RgbdCamera& cam, const mrpt::poses::CPose3D& T_world_cam) {
		maps::markSeenCells(gt, depth, cam, T_world_cam, vis);
	});
}

}  // namespace

MapEvaluationResult evaluateMapAgainstFloorPlan(
	const MapEvaluationOptions& o, const eval::Similarity3& T_gt_est, const core::Trajectory& gtTraj)
{
	if (o.mapYaml.empty() || o.floorPlanYaml.empty())
		throw std::invalid_argument("map evaluation needs both a map and a floor plan");
	if (o.scenePath.empty() != o.keyframesPath.empty())
		throw std::invalid_argument("the visibility mask needs both a scene and a keyframes file");
	for (const auto& p : {o.mapYaml, o.floorPlanYaml})
		if (!mrpt::system::fileExists(p)) throw std::runtime_error("'" + p + "' does not exist");
	maps::FloorPlanGrid gt = toFloorPlanGrid(sim::FloorPlan::load(o.floorPlanYaml));
	const maps::TriStateGrid est = maps::TriStateGrid::loadRosMapServer(o.mapYaml);
	if (!est.T_world_floor)
		throw std::runtime_error(
			"'" + o.mapYaml + "' has no '# keygrid T_world_floor' line (a map_2d.yaml written by keygrid-slam has it)");

	MapEvaluationResult r;
	// x_gt = s R (T_world_floor p) + t = T_gt_floor (s p), with T_gt_floor = (R R_wf, s R t_wf + t):
	// the rigid frame of the floor in the ground-truth world, the grid's unit scaled by s.
	const mrpt::poses::CPose3D& T_wf = *est.T_world_floor;
	eval::Similarity3 floorFrame;
	floorFrame.R = T_gt_est.R * T_wf.getRotationMatrix().asEigen();
	floorFrame.t = T_gt_est.apply(Eigen::Vector3d(T_wf.x(), T_wf.y(), T_wf.z()));
	const mrpt::poses::CPose3D T_gt_floor = eval::rigidPose(floorFrame);
	r.floorOffset = T_gt_floor.z();
	const auto R = T_gt_floor.getRotationMatrix();
	r.floorTiltDeg = std::acos(std::min(1.0, std::abs(R(2, 2)))) * 180.0 / M_PI;

	const maps::TriStateGrid onPlan = maps::resampleTriState(est, T_gt_floor, gt, T_gt_est.s);

	if (!o.scenePath.empty()) r.visibilityKeyframes = markVisibility(gt, o, gtTraj);
	r.metrics = maps::evaluateOccupancy(onPlan, gt, o.metrics);
	if (!o.overlayPath.empty())
	{
		const auto counts = maps::saveOverlayImage(o.overlayPath, onPlan, gt, o.metrics, o.overlay);
		std::copy(counts.begin(), counts.end(), r.verdicts.begin());
	}
	else
		for (const auto v : maps::classifyCells(onPlan, gt, o.metrics)) r.verdicts[static_cast<std::size_t>(v)]++;
	return r;
}

std::string MapEvaluationResult::toText() const
{
	const auto& m = metrics;
	char b[2048];
	std::snprintf(
		b, sizeof(b),
		"map vs floor plan (%s):\n"
		"  floor: estimated floor %+.4f m above the true one at its origin, tilted %.2f deg\n"
		"  hazard cells %zu (interior obstacle cells called free, of %zu); obstacle cells called free %zu\n"
		"  obstacle recall, boundary cells seen %.4f (%zu of %zu); all obstacle cells %.4f (%zu of %zu)\n"
		"  obstacle precision %.4f (%zu of %zu)\n"
		"  free space F1 %.4f: precision %.4f (%zu of %zu), recall %.4f (%zu of %zu %s)\n"
		"  free space F1 over the cells whose floor was in view %.4f: recall %.4f (%zu of %zu)\n",
		visibilityKeyframes ? ("visibility from " + std::to_string(visibilityKeyframes) + " keyframes").c_str()
							: "no visibility mask: every cell counts as seen",
		floorOffset, floorTiltDeg, m.hazardCells, m.gtOccupiedInterior, m.gtOccupiedCalledFree, m.boundaryRecall,
		m.gtBoundarySeenMatched, m.gtBoundarySeen, m.recall, m.gtOccupiedMatched, m.gtOccupied, m.precision,
		m.estOccupiedMatched, m.estOccupied, m.freeF1, m.freePrecision, m.estFreeCorrect, m.estFree, m.freeRecall,
		m.gtFreeSeenCalledFree, m.gtFreeSeen, visibilityKeyframes ? "free cells in view" : "free cells",
		m.freeF1FloorSeen, m.freeRecallFloorSeen, m.gtFreeFloorSeenCalledFree, m.gtFreeFloorSeen);
	std::ostringstream o;
	o << b << "  cells:";
	for (int i = 0; i < maps::kCellVerdictCount; i++)
		o << (i ? ", " : " ") << maps::cellVerdictName(static_cast<maps::CellVerdict>(i)) << " " << verdicts[i];
	o << "\n";
	return o.str();
}

std::string MapEvaluationResult::jsonFields() const
{
	const auto& m = metrics;
	std::ostringstream o;
	o << "  \"map_hazard_cells\": " << m.hazardCells << ",\n"
	  << "  \"map_interior_obstacle_cells\": " << m.gtOccupiedInterior << ",\n"
	  << "  \"map_obstacle_called_free_cells\": " << m.gtOccupiedCalledFree << ",\n"
	  << "  \"map_boundary_recall\": " << core::jsonNumber(m.boundaryRecall, 6) << ",\n"
	  << "  \"map_boundary_cells_seen\": " << m.gtBoundarySeen << ",\n"
	  << "  \"map_obstacle_precision\": " << core::jsonNumber(m.precision, 6) << ",\n"
	  << "  \"map_obstacle_recall\": " << core::jsonNumber(m.recall, 6) << ",\n"
	  << "  \"map_free_precision\": " << core::jsonNumber(m.freePrecision, 6) << ",\n"
	  << "  \"map_free_recall\": " << core::jsonNumber(m.freeRecall, 6) << ",\n"
	  << "  \"map_free_f1\": " << core::jsonNumber(m.freeF1, 6) << ",\n"
	  << "  \"map_free_cells_seen\": " << m.gtFreeSeen << ",\n"
	  << "  \"map_free_recall_floor_seen\": " << core::jsonNumber(m.freeRecallFloorSeen, 6) << ",\n"
	  << "  \"map_free_f1_floor_seen\": " << core::jsonNumber(m.freeF1FloorSeen, 6) << ",\n"
	  << "  \"map_free_cells_floor_seen\": " << m.gtFreeFloorSeen << ",\n"
	  << "  \"map_floor_offset_m\": " << core::jsonNumber(floorOffset, 6) << ",\n"
	  << "  \"map_floor_tilt_deg\": " << core::jsonNumber(floorTiltDeg, 6) << ",\n"
	  << "  \"map_visibility_keyframes\": " << visibilityKeyframes;
	return o.str();
}

}  // namespace keygrid::slam
