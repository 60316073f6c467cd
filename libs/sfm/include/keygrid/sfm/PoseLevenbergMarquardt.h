#pragma once
/** \file PoseLevenbergMarquardt.h
 * A dedicated Levenberg-Marquardt solver for one camera pose against fixed 3D points: the
 * inner solve of optimizePose(), on every tracked frame and again for every frame of the
 * final refinement. It minimises the same cost as a Ceres problem of AnalyticReprojectionCost
 * residual blocks with a Huber loss, without building a problem per solve: a 6x6 normal
 * equation accumulated observation by observation.
 *
 * Pose: T_cam_world = (R, t), p_cam = R p_world + t. A step (w, dt) in the tangent space
 * updates R <- Exp(w) R, t <- t + dt, so d p_cam / d w = -[R p_world]x and d p_cam / d dt = I.
 *
 * Residuals of observation i (RgbdReprojectionCost.h): r = ((u_obs - u) s, (v_obs - v) s,
 * (bf / d_obs - bf / z) s_d), the third only with depth; cost = 1/2 sum_i rho_i(|r_i|^2).
 * Huber with threshold delta: rho(s) = s for s <= delta^2, 2 delta sqrt(s) - delta^2 beyond.
 * Like Ceres, each block's residual and Jacobian are scaled by sqrt(rho'(s)) (its second
 * derivative is <= 0, so Ceres' Triggs correction reduces to this re-weighting), so each
 * iteration solves (J^T W J + D / radius) step = -J^T W r with W = rho'(s) and
 * D = diag(J^T W J) clamped to [1e-6, 1e32].
 *
 * Trust region and stopping as Ceres' LM defaults: a step is accepted when the actual cost
 * decrease is more than 1e-3 of the model's; the radius grows by 1 / max(1/3, 1 - (2 rho - 1)^3)
 * after an accepted step and halves (then quarters, ...) after a rejected one, which also
 * covers a step that puts a point behind the camera. Stops when the relative cost decrease
 * falls below functionTolerance, the gradient's max norm below gradientTolerance, the step
 * below parameterTolerance (|x| + parameterTolerance), or after maxIterations iterations
 * (accepted or not).
 */
#include <keygrid/sfm/RgbdReprojectionCost.h>

#include <Eigen/Core>
#include <vector>

namespace keygrid::sfm
{
/** What one keypoint measured, with its weights: the residual's constants (see above). */
struct ReprojectionMeasurement
{
	Eigen::Vector2d uv{Eigen::Vector2d::Zero()};  //!< undistorted pixel
	double invSigma{1};                           //!< 1 / sigma_level on (u, v)
	double disparity{0};                          //!< bf / d_obs; 0: no depth residual
	double invSigmaDisparity{0};                  //!< 1 / sigma_disparity
	double huberDelta{0};                         //!< Huber threshold on |r|; 0: plain least squares
};

/** One observation of a fixed point, in the form the solver evaluates. */
struct PoseResidualTerm : ReprojectionMeasurement
{
	Eigen::Vector3d p_world{Eigen::Vector3d::Zero()};
};

/** Stopping rules and the start of the trust region of the dedicated Levenberg-Marquardt
 * solvers (this one and BundleLevenbergMarquardt.h), as Ceres' options of the same names. */
struct LevenbergMarquardtOptions
{
	int maxIterations{10};
	double functionTolerance{1e-6};
	double gradientTolerance{1e-10};
	double parameterTolerance{1e-8};
	double initialTrustRegionRadius{1e4};
};
using PoseSolverOptions = LevenbergMarquardtOptions;

struct PoseSolverSummary
{
	double initialCost{0}, finalCost{0};
	int iterations{0};           //!< accepted and rejected steps
	int successfulIterations{0};
	bool usable{true};           //!< false: some point behind the camera at the start (nothing done)
};

/** Squared residual |r|^2 of `term` at (R, t), no robust loss; false when the point is not in
 * front of the camera (z <= 1e-6). */
bool poseResidualSquaredNorm(
	const Eigen::Matrix3d& R_cam_world, const Eigen::Vector3d& t_cam_world, const PoseResidualTerm& term,
	const PinholeIntrinsics& K, double bf, double& squaredNorm);

/** Minimises the robust cost of `terms` over (R, t) in place (see the file comment). */
PoseSolverSummary solvePoseLevenbergMarquardt(
	Eigen::Matrix3d& R_cam_world, Eigen::Vector3d& t_cam_world, const std::vector<PoseResidualTerm>& terms,
	const PinholeIntrinsics& K, double bf, const PoseSolverOptions& opts = {});

}  // namespace keygrid::sfm
