#pragma once
/** \file LandmarkState.h
 * sfm::LandmarkState — a landmark of the frontend's map apart from its Histogram of Oriented
 * Cameras: sfm::Landmark adds the histogram, store::LandmarkRecord its stored bin counts.
 */
#include <keygrid/sfm/Ids.h>
#include <opencv2/core.hpp>

#include <Eigen/Core>
#include <map>

namespace keygrid::sfm
{
struct LandmarkState
{
	LandmarkId id{0};
	/** Position in the world frame [m] */
	Eigen::Vector3d p_world{Eigen::Vector3d::Zero()};
	/** Representative descriptor (one row): the one with the least median distance to the
	 * others. */
	cv::Mat descriptor;
	/** keyframe -> index of the keypoint observing this landmark there */
	std::map<KeyFrameId, int> observations;
	/** Mean viewing direction (unit, world frame, from cameras towards the point). */
	Eigen::Vector3d normal{Eigen::Vector3d::Zero()};
	/** Distances within which ORB's scale invariance holds [m]. */
	double minDistance{0}, maxDistance{0};
	KeyFrameId firstKeyFrame{0};
	/** Frames where it was predicted in view / actually matched (for culling). */
	int visibleCount{1}, foundCount{1};
};

}  // namespace keygrid::sfm
