#pragma once
/** \file MapEvaluation.h
 * keygrid-eval's map mode: keygrid-slam's 2D grid (map_2d.yaml) scored against keygrid-sim's
 * ground-truth floor plan. The grid's floor frame (the yaml's `# keygrid T_world_floor` line, in
 * the SLAM world) is carried into the ground-truth world by the trajectory alignment, the grid
 * resampled onto the plan's lattice (nearest cell centre) and scored with the navigation-safety
 * metrics of keygrid/maps/OccupancyGridMetrics.h; optionally the plan's visibility mask is
 * rendered from the scene at the keyframes' ground-truth poses, and the overlay image written.
 * It lives in libs/slam because it needs maps, sim and eval (libs/eval must not depend on maps).
 */
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/eval/Alignment.h>
#include <keygrid/maps/OccupancyGridMetrics.h>
#include <mrpt/poses/CPose3D.h>

#include <array>
#include <string>

namespace keygrid::slam
{
struct MapEvaluationOptions
{
	/** keygrid-slam's map_2d.yaml (+ its .pgm); must carry the `# keygrid T_world_floor` line */
	std::string mapYaml;
	/** keygrid-sim's floorplan.yaml (+ .pgm): the ground truth, world frame z up, floor z = 0 */
	std::string floorPlanYaml;
	/** Scene INI the plan was rendered from; with keyframesPath: the visibility mask (Default:
	 * empty = no mask, every cell counts as in view) */
	std::string scenePath;
	/** TUM file whose timestamps are the keyframes (keygrid-slam's keyframes.txt); each is
	 * rendered noise-free at its ground-truth pose (Default: empty) */
	std::string keyframesPath;
	/** Overlay image to write (PNG) (Default: empty = none) */
	std::string overlayPath;
	maps::OccupancyMetricsOptions metrics;
	maps::OverlayImageOptions overlay;
	/** Band, range and ray stride of the visibility mask. zMin / zMax are replaced by the scene's
	 * [output] floorplan_z_min / floorplan_z_max (the plan's own band) when a scene is given. */
	maps::FloorPlanVisibilityOptions visibility;
	/** Largest |t_keyframe - t_gt| for a keyframe's ground-truth pose [s] (Default: 0.02 s) */
	double maxDt{0.02};
	/** Progress bar while rendering the keyframes (Default: false) */
	bool progress{false};
};

struct MapEvaluationResult
{
	maps::OccupancyMetrics metrics;
	/** Estimated floor in the ground-truth world: height of its frame's origin (under the first
	 * keyframe's camera) above the true floor z = 0 [m], and the angle between its normal and
	 * the true z axis [deg]. */
	double floorOffset{0}, floorTiltDeg{0};
	/** Keyframes rendered for the visibility mask (0 = no mask). */
	std::size_t visibilityKeyframes{0};
	/** Cells per verdict (index = maps::CellVerdict) on the plan's lattice. */
	std::array<std::size_t, maps::kCellVerdictCount> verdicts{};

	/** Human-readable lines. */
	std::string toText() const;
	/** `"map_...": value` lines (no braces) for keygrid-eval's JSON: map_hazard_cells,
	 * map_interior_obstacle_cells, map_obstacle_called_free_cells, map_boundary_recall,
	 * map_boundary_cells_seen, map_obstacle_precision, map_obstacle_recall, map_free_precision,
	 * map_free_recall, map_free_f1, map_free_cells_seen, map_floor_offset_m, map_floor_tilt_deg,
	 * map_visibility_keyframes. */
	std::string jsonFields() const;
};

/** Scores opts.mapYaml against opts.floorPlanYaml. T_gt_est maps the SLAM world into the
 * ground-truth world (keygrid-eval's alignment: SE(3), or Sim(3) for a map in another unit,
 * whose cells are then scaled by T_gt_est.s); gt is the ground-truth trajectory (for the
 * keyframes' poses). Throws std::runtime_error / std::invalid_argument naming the bad input. */
MapEvaluationResult evaluateMapAgainstFloorPlan(
	const MapEvaluationOptions& opts, const eval::Similarity3& T_gt_est, const core::Trajectory& gt);

}  // namespace keygrid::slam
