#pragma once
/** \file PnpSolver.h
 * Camera pose from 2D-3D correspondences with RANSAC (OpenCV EPnP minimal sets, seeded so a
 * run is reproducible), used when the motion-model prediction fails and for relocalization.
 */
#include <keygrid/sfm/RgbdReprojectionCost.h>
#include <mrpt/poses/CPose3D.h>

#include <vector>

namespace keygrid::sfm
{
struct PnpOptions
{
	/** RANSAC iterations (Default: 200) */
	int iterations{200};
	/** Inlier reprojection threshold [px] (Default: 4) */
	double reprojectionError{4.0};
	/** Success needs at least this many inliers (Default: 15) */
	int minInliers{15};
	/** RNG seed, fixed for reproducible runs (Default: 12345) */
	uint64_t seed{12345};
};

struct PnpResult
{
	bool ok{false};
	mrpt::poses::CPose3D T_world_cam;
	std::vector<int> inliers;  //!< indices into the correspondence lists
};

/** points_world[i] <-> pixels[i] (undistorted). */
PnpResult solvePnpRansac(
	const std::vector<Eigen::Vector3d>& points_world, const std::vector<Eigen::Vector2d>& pixels,
	const PinholeIntrinsics& K, const PnpOptions& opts = {});

}  // namespace keygrid::sfm
