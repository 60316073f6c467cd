#pragma once
/** \file FinalRefinement.h
 * Pieces of the final step of a run (System::finish()): which keyframes a bounded final bundle
 * adjustment grows from, how far the refinement moved the keyframes (do the maps need
 * re-anchoring?), and the re-estimation of frame poses against the refined map.
 */
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/loop/LoopCloser.h>
#include <keygrid/sfm/Tracker.h>
#include <keygrid/slam/SlamConfig.h>

#include <functional>
#include <map>
#include <optional>
#include <set>
#include <vector>

namespace keygrid::slam
{
/** Seeds of the bounded final bundle adjustment (sfm::growBundleWindow): both ends of every
 * closed loop, the newest loop first (there the pose graph bent the trajectory and landmarks
 * were fused), then the newest keyframe (refined by the fewest local windows). */
std::vector<sfm::KeyFrameId> finalWindowSeeds(const std::vector<loop::LoopClosureEvent>& loops, const sfm::SparseMap& map);

struct FinalBundleAdjustment
{
	sfm::BundleAdjusterReport report;
	/** The keyframes it moved when bounded; nullopt when it moved every keyframe */
	std::optional<std::set<sfm::KeyFrameId>> window;
	/** Monocular (holdScale): the factor the adjustment had scaled the map by, undone after it
	 * (1 when the scale was not held) */
	double undoneScale{1.0};
};

/** The scale of the similarity that best maps the keyframe centres of `before` onto those of
 * `after` (the keyframes in both; Umeyama's least squares); 1 for fewer than two. */
double scaleBetween(const std::map<sfm::KeyFrameId, mrpt::poses::CPose3D>& before, const std::map<sfm::KeyFrameId, mrpt::poses::CPose3D>& after);

/** The final bundle adjustment of a run, in place: every keyframe and landmark (the first
 * keyframe fixed), or in a map of more than rc.globalMaxKeyFrames keyframes the window grown
 * from finalWindowSeeds(). The local windows' options `mapping.ba`, with rc.globalIterations
 * and Ceres' default tolerance (it runs once, to convergence); a landmark without a depth
 * measurement whose rays meet at less than mapping.minParallaxDeg stays out.
 * holdScale (a map without depth): the reprojection errors do not change when the whole map
 * is scaled about the fixed keyframe, so the adjustment's own scale is arbitrary: the map's
 * scale before it (metres from the camera height, or the unit the run kept) is restored. */
FinalBundleAdjustment finalBundleAdjustment(
	sfm::SparseMap& map, const sfm::PinholeIntrinsics& K, const std::vector<loop::LoopClosureEvent>& loops,
	const RefinementOptions& rc, const sfm::LocalMapperOptions& mapping, bool holdScale = false);

/** Largest displacement [m], over the keyframes of `before` that are in `after`, of the camera
 * centre or of the point `depth` m ahead of it on the optical axis (what a rotation moves in
 * the maps). */
double largestDisplacement(
	const std::map<sfm::KeyFrameId, mrpt::poses::CPose3D>& before,
	const std::map<sfm::KeyFrameId, mrpt::poses::CPose3D>& after, double depth);

/** Re-estimates the pose of every tracked frame that `select` accepts against the landmarks
 * now in `map` (each starting from `base`, its pose before), from the inlier observations it
 * kept, with the pose solver's options `pose`; a frame keeps no re-estimate (nullopt) when
 * fewer than minInliers observations remain or are inliers. Frames are independent: two
 * workers (every other frame each) read the map and write their own entries, so the result
 * does not depend on scheduling. */
std::vector<std::optional<mrpt::poses::CPose3D>> refineFramePoses(
	const std::vector<sfm::TrackedFrame>& frames, const core::Trajectory& base, const sfm::SparseMap& map,
	const sfm::PinholeIntrinsics& K, const sfm::PoseOptimizerOptions& pose, int minInliers,
	const std::function<bool(const sfm::TrackedFrame&)>& select);

}  // namespace keygrid::slam
