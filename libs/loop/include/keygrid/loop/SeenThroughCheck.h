#pragma once
/** \file SeenThroughCheck.h
 * Free-space test of a hypothesised relative pose between two keyframes (a map merge, see
 * LoopCloser): landmarks of one side are projected into the other keyframe, and the depth of
 * the keypoints found there says whether the camera sees the landmark (depth agrees), sees
 * something in front of it (occlusion: no evidence either way), or sees *through* it (the
 * measured surface lies behind the landmark: there is free space where the hypothesis puts
 * a point). Look-alike places that pass descriptor matching and 3D RANSAC, e.g. a corridor
 * whose wall texture repeats, put the other side's points in front of or behind the true
 * surfaces; the points put in front are seen through from one of the two keyframes.
 */
#include <keygrid/sfm/RgbdReprojectionCost.h>
#include <keygrid/sfm/SparseMap.h>

#include <Eigen/Geometry>
#include <vector>

namespace keygrid::loop
{
struct SeenThroughCount
{
	int agreeing{0};  //!< landmarks whose depth the target keyframe measures
	int seenThrough{0};  //!< landmarks the target keyframe sees through
	/** seenThrough / (agreeing + seenThrough); 0 when neither */
	double ratio() const { return agreeing + seenThrough > 0 ? static_cast<double>(seenThrough) / (agreeing + seenThrough) : 0.0; }
	SeenThroughCount& operator+=(const SeenThroughCount& o)
	{
		agreeing += o.agreeing;
		seenThrough += o.seenThrough;
		return *this;
	}
};

/** The landmarks observed by `sources`, moved by T_target_points into the camera frame of
 * keyframe `target` and projected with K: each is compared with the nearest keypoint with
 * depth within `radiusPx` of its projection. A depth within relTolerance x depth +
 * absTolerance of the landmark's agrees; a depth farther than that is seen through. */
SeenThroughCount countSeenThrough(
	const sfm::SparseMap& map, const std::vector<sfm::KeyFrameId>& sources, const Eigen::Isometry3d& T_target_points,
	const sfm::KeyFrame& target, const sfm::PinholeIntrinsics& K, float radiusPx = 4.f, double relTolerance = 0.1,
	double absTolerance = 0.05);

}  // namespace keygrid::loop
