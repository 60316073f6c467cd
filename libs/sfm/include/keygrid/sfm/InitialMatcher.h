#pragma once
/** \file InitialMatcher.h
 * Matching of a frame against the reference frame of a monocular map start (ORB-SLAM's
 * SearchForInitialization): there is no map and no pose yet, so each reference keypoint is
 * searched in a window around where it was last matched, at its own pyramid level (+-1), and
 * the best candidate is kept when it is close and distinct enough; each current keypoint keeps
 * its best reference keypoint, and optionally only matches whose orientation change agrees
 * with the bulk (a rigid motion turns every keypoint about alike) survive.
 */
#include <keygrid/sfm/FrameFeatures.h>

#include <vector>

namespace keygrid::sfm
{
struct InitialMatchOptions
{
	/** Search radius around the predicted position [px at level 0] (Default: 100) */
	float windowPx{100.f};
	/** Largest descriptor distance of a match: Hamming bits for ORB, L2 for SIFT (Default: 50) */
	float maxDistance{50.f};
	/** Best / second-best distance ratio (Default: 0.9) */
	float ratio{0.9f};
	/** Keep matches whose orientation change falls in the three fullest of 30 bins (Default: true) */
	bool checkOrientation{true};
};

/** Matches of `ref` in `cur`: `refToCur[i]` is the current keypoint of reference keypoint i
 * (-1 when none). `predicted[i]` is where reference keypoint i is searched (its position in
 * the last frame it was matched in; the reference positions for the first frame); on return
 * the matched entries hold their new positions. Returns the number of matches. Throws
 * std::invalid_argument when `predicted` does not have one entry per reference keypoint. */
int searchForInitialization(
	const FrameFeatures& ref, const FrameFeatures& cur, std::vector<cv::Point2f>& predicted, const InitialMatchOptions& o,
	std::vector<int>& refToCur);

}  // namespace keygrid::sfm
