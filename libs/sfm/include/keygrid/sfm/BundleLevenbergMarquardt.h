#pragma once
/** \file BundleLevenbergMarquardt.h
 * A dedicated Levenberg-Marquardt bundle adjustment for large problems (the final global
 * adjustment of a map): the same robust cost as a Ceres problem of AnalyticReprojectionCost
 * residual blocks with Huber losses, solved with the points eliminated first (Schur
 * complement) and the reduced camera system factored by CHOLMOD's supernodal Cholesky.
 *
 * Camera i: T_cam_world = (R_i, t_i), p_cam = R_i p + t_i; a step (w, dt) updates
 * R_i <- Exp(w) R_i, t_i <- t_i + dt, so d p_cam / d w = -[R_i p]x, d p_cam / d dt = I and
 * d p_cam / d p = R_i. Residuals and the Huber re-weighting as the pose solver
 * (PoseLevenbergMarquardt.h); trust region and stopping rules as Ceres' LM defaults.
 *
 * One iteration solves the damped normal equations
 *     [ U + D_c    W     ] [dc]     [g_c]
 *     [ W^T      V + D_p ] [dp] = - [g_p]
 * (U: camera blocks of J^T W J, V: point blocks (3x3, one per point), W: camera-point blocks,
 * D = diag(J^T W J) / radius) by eliminating the points:
 *     (U + D_c - W (V + D_p)^-1 W^T) dc = -g_c + W (V + D_p)^-1 g_p,
 *     dp_j = (V_j + D_pj)^-1 (-g_pj - sum_i W_ij^T dc_i).
 * The reduced matrix has one 6x6 block per pair of moving cameras sharing a point.
 *
 * The points are split into two fixed halves worked on by two threads, each summing into its
 * own copy; the copies are added in a fixed order, so the result does not depend on the
 * threads' timing (runs are bit-identical).
 */
#include <keygrid/sfm/PoseLevenbergMarquardt.h>

#include <Eigen/Core>
#include <vector>

namespace keygrid::sfm
{
struct BundleCamera
{
	Eigen::Matrix3d R_cam_world{Eigen::Matrix3d::Identity()};
	Eigen::Vector3d t_cam_world{Eigen::Vector3d::Zero()};
	/** A fixed camera only anchors the points it sees. */
	bool fixed{false};
};

/** One observation of point `point` by camera `camera` (indices into the solver's arrays). */
struct BundleTerm : ReprojectionMeasurement
{
	int camera{0};
	int point{0};
};

/** As the pose solver's; BundleAdjustment passes its own iteration limit and tolerance. */
using BundleSolverOptions = LevenbergMarquardtOptions;

/** The pose solver's summary (usable: false when some point is behind its camera at the
 * start, nothing done), with where the time went. */
struct BundleSolverSummary : PoseSolverSummary
{
	/** residual and Jacobian evaluations; elimination, factorization and back-substitution [s] */
	double evaluationSeconds{0}, linearSolverSeconds{0};
};

/** Squared residual |r|^2 of `term` for a camera and point, no robust loss; false when the
 * point is not in front of the camera (z <= 1e-6). */
bool bundleResidualSquaredNorm(
	const BundleCamera& camera, const Eigen::Vector3d& point, const BundleTerm& term, const PinholeIntrinsics& K,
	double bf, double& squaredNorm);

/** Minimises the robust cost of `terms` over the moving cameras and all points, in place (see
 * the file comment). The terms must be sorted by point. Throws std::invalid_argument for a
 * term whose camera or point index is out of range, or terms out of order. */
BundleSolverSummary solveBundleLevenbergMarquardt(
	std::vector<BundleCamera>& cameras, std::vector<Eigen::Vector3d>& points, const std::vector<BundleTerm>& terms,
	const PinholeIntrinsics& K, double bf, const BundleSolverOptions& opts = {});

}  // namespace keygrid::sfm
