#pragma once
/** \file Grid3DEvaluation.h
 * keygrid-eval's 3D grid mode: keygrid-slam's map_3d.bt scored against keygrid-sim's
 * ground-truth voxels (occupancy_voxels.txt) with eval::evaluateVoxelMap. The .bt's frame (its
 * `# keygrid T_world_floor` header line, in the SLAM world; no line = the SLAM world itself) is
 * carried into the ground-truth world by the trajectory alignment; optionally the true voxels the
 * keyframe cameras saw are found by rendering the scene at their ground-truth poses.
 * It lives in libs/slam because it needs maps, sim and eval (libs/eval must not depend on them).
 */
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/eval/Alignment.h>
#include <keygrid/eval/VoxelMapMetrics.h>

#include <string>

namespace keygrid::slam
{
struct Grid3DEvaluationOptions
{
	/** keygrid-slam's map_3d.bt (OctoMap binary) */
	std::string gridBt;
	/** keygrid-sim's occupancy_voxels.txt: the ground truth, world frame z up */
	std::string voxelsPath;
	/** Scene INI the voxels were rendered from; with keyframesPath: the seen mask (Default:
	 * empty = no mask, every true voxel counts as seen) */
	std::string scenePath;
	/** keygrid-slam's keyframes.txt, with scenePath (Default: empty) */
	std::string keyframesPath;
	eval::VoxelMapMetricsOptions metrics;
	/** A rendered surface point farther than this from its camera is not seen [m] (Default: 4 m,
	 * the 3D grid's insertion range in config/sim*.ini) */
	double maxRange{4.0};
	/** Largest |t_keyframe - t_gt| for a keyframe's ground-truth pose [s] (Default: 0.02 s) */
	double maxDt{0.02};
	/** Progress bar while rendering the keyframes (Default: false) */
	bool progress{false};

	bool isValid(std::string* error = nullptr) const;
};

struct Grid3DEvaluationResult
{
	eval::VoxelMapMetrics metrics;
	/** Voxel size of the map [its unit: m, or a monocular map's unit] */
	double resolution{0};
	/** The alignment's scale: the map's voxels measure resolution * scale in the ground truth */
	double scale{1};
	/** Whether the .bt was in a floor frame (else in the SLAM world). */
	bool floorFrame{false};
	/** Keyframes rendered for the seen mask (0 = no mask). */
	std::size_t visibilityKeyframes{0};

	/** Human-readable lines. */
	std::string toText() const;
	/** `"grid3d_...": value` lines (no braces) for keygrid-eval's JSON: the fields of
	 * eval::VoxelMapMetrics::jsonFields, grid3d_resolution, grid3d_voxel_size_m (in the ground
	 * truth, after the alignment's scale), grid3d_floor_frame,
	 * grid3d_visibility_keyframes. */
	std::string jsonFields() const;
};

/** Scores opts.gridBt against opts.voxelsPath. T_gt_est maps the SLAM world into the ground-truth
 * world (keygrid-eval's alignment, SE(3) or Sim(3)); gt is the ground-truth trajectory (for the
 * keyframes' poses). Throws std::runtime_error / std::invalid_argument naming the bad input. */
Grid3DEvaluationResult evaluateGrid3DAgainstVoxels(
	const Grid3DEvaluationOptions& opts, const eval::Similarity3& T_gt_est, const core::Trajectory& gt);

}  // namespace keygrid::slam
