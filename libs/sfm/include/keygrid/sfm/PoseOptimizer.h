#pragma once
/** \file PoseOptimizer.h
 * Pose-only refinement of one camera against fixed 3D landmarks (Ceres, Huber loss,
 * reprojection + depth residuals), with ORB-SLAM2-style rounds of outlier classification.
 */
#include <keygrid/sfm/RgbdReprojectionCost.h>
#include <mrpt/poses/CPose3D.h>

#include <vector>

namespace keygrid::sfm
{
struct PoseObservation
{
	Eigen::Vector3d p_world{Eigen::Vector3d::Zero()};
	Eigen::Vector2d uv{Eigen::Vector2d::Zero()};  //!< undistorted pixel
	double depth{0};     //!< measured depth [m], 0 = none
	double invSigma{1};  //!< 1 / scaleFactor^level
};

struct PoseOptimizerOptions
{
	/** Outlier-classification rounds (Default: 4) */
	int rounds{4};
	/** Levenberg-Marquardt iterations per round (Default: 10) */
	int iterationsPerRound{10};
	/** Chi-square inlier thresholds, 95 % for 2 and 3 DOF (Default: 5.991, 7.815) */
	double chi2Mono{5.991}, chi2Rgbd{7.815};
	/** Virtual stereo baseline x fx [px m] (Default: 40, Kinect-like, as ORB-SLAM2's TUM configs) */
	double bf{40.0};
	/** Standard deviation of the virtual disparity bf / depth [px], the same at every pyramid
	 * level; depth noise sigma_z = disparitySigma z^2 / bf (Default: 0.25; with bf = 40,
	 * 6.25 mm z^2 [m]: about 4x the Kinect's sensor noise, for the depth read at corner
	 * keypoints and the RGB/depth registration; see RgbdReprojectionCost.h) */
	double disparitySigma{0.25};
	/** Depth residuals only for depths below this [m] (Default: 6 m) */
	double maxDepthForRgbd{6.0};
};

struct PoseOptimizerResult
{
	int inliers{0};
	std::vector<char> inlier;  //!< per observation
	double rmsPixels{0};       //!< RMS of inlier (u,v) reprojection errors [px]
};

/** Refines T_world_cam in place. Observations classified as outliers in the last round are
 * marked in `inlier`. Throws std::invalid_argument on an empty observation set. */
PoseOptimizerResult optimizePose(
	mrpt::poses::CPose3D& T_world_cam, const std::vector<PoseObservation>& obs,
	const PinholeIntrinsics& K, const PoseOptimizerOptions& opts = {});

/** Conversions between CPose3D T_world_cam and the (q, t) of T_cam_world used by the costs. */
void toCeres(const mrpt::poses::CPose3D& T_world_cam, double q_cam_world[4], double t_cam_world[3]);
mrpt::poses::CPose3D fromCeres(const double q_cam_world[4], const double t_cam_world[3]);

}  // namespace keygrid::sfm
