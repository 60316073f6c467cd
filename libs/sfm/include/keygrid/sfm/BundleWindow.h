#pragma once
/** \file BundleWindow.h
 * Which keyframes a bounded bundle adjustment moves and which anchor it. The final refinement
 * of a long run uses it instead of optimising every keyframe: the map was refined by local
 * bundle adjustments all along, so what is left to reconcile is where a loop closure bent the
 * trajectory (the two ends of each loop, whose landmarks were fused) and the newest keyframes
 * (refined by few local windows); the cost then follows the window, not the map.
 */
#include <keygrid/sfm/SparseMap.h>

#include <cstddef>
#include <set>
#include <vector>

namespace keygrid::sfm
{
struct BundleWindow
{
	/** Keyframes optimised, in the order they joined the window. */
	std::vector<KeyFrameId> local;
	/** Keyframes outside the window that observe its landmarks: held fixed, they keep the
	 * window attached to the rest of the map. */
	std::set<KeyFrameId> fixed;
};

/** Grows a window from `seeds` through the covisibility graph, breadth first: every seed,
 * then the covisible keyframes of the seeds (ring 1), then theirs (ring 2), ...; within a ring
 * in the order of the keyframes they were reached from, each one's neighbours by decreasing
 * covisibility weight (then id). Stops at `maxKeyFrames` (>= 1). Seeds that are not in the
 * map (culled keyframes) and repeated seeds are skipped. `fixed` holds every other keyframe
 * that observes a landmark seen by the window. */
BundleWindow growBundleWindow(const SparseMap& map, const std::vector<KeyFrameId>& seeds, std::size_t maxKeyFrames);

}  // namespace keygrid::sfm
