#pragma once
/** \file PoseOptimizer.h
 * Pose-only refinement of one camera against fixed 3D landmarks (reprojection + depth
 * residuals, Huber loss), with ORB-SLAM2-style rounds of outlier classification; each round is
 * solved by the dedicated Levenberg-Marquardt solver of PoseLevenbergMarquardt.h.
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

/** Squared normalised residual of one observation at T_world_cam, without robust loss: (u, v)
 * divided by sigma_level, plus the disparity term for depths below maxDepthForRgbd (the
 * quantity optimizePose compares with its chi-square thresholds). +inf when the point is not
 * in front of the camera. */
double observationChi2(
	const mrpt::poses::CPose3D& T_world_cam, const PoseObservation& ob, const PinholeIntrinsics& K,
	const PoseOptimizerOptions& opts);

/** The chi-square inlier threshold of `ob`: chi2Rgbd when its depth residual is used, chi2Mono
 * otherwise. */
double inlierThreshold(const PoseObservation& ob, const PoseOptimizerOptions& opts);

/** Anchored pose refinement: keeps a moving object from dragging the pose.
 *
 * A person walking past the camera is matched frame after frame by projection search, so its
 * landmarks pass every per-frame outlier test; when the static points are far and shallow
 * (one depth layer) they cannot tell a sideways translation t from a rotation t / depth, and
 * the walker's points decide the pose, which then drifts with the walker (keygrid-sim's
 * moving_camera_dynamic scene). The walker's landmarks are young: each new keyframe
 * re-creates them. Landmarks seen by several keyframes are what the map has confirmed.
 *
 * So: (1) refine the pose from the anchors alone (isAnchor[i]); (2) drop the other
 * observations whose chi2 at that pose exceeds chi2Factor x their inlier threshold; (3) refine
 * from the anchored pose with all remaining observations (optimizePose). The factor is loose
 * (9 = 3 sigma in residual units) because young static points must stay: they carry the new
 * parts of the view, and older landmarks carry the map's own small accumulated error. Fewer
 * than minAnchors anchors: plain optimizePose. Observations dropped in (2) are outliers of the
 * result; `rejected` receives their number. */
PoseOptimizerResult optimizePoseAnchored(
	mrpt::poses::CPose3D& T_world_cam, const std::vector<PoseObservation>& obs, const std::vector<char>& isAnchor,
	const PinholeIntrinsics& K, const PoseOptimizerOptions& opts, double chi2Factor, int minAnchors,
	int* rejected = nullptr);

/** Conversions between CPose3D T_world_cam and the (q, t) of T_cam_world used by the costs. */
void toCeres(const mrpt::poses::CPose3D& T_world_cam, double q_cam_world[4], double t_cam_world[3]);
mrpt::poses::CPose3D fromCeres(const double q_cam_world[4], const double t_cam_world[3]);

}  // namespace keygrid::sfm
