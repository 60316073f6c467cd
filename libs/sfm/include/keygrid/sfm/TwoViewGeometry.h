#pragma once
/** \file TwoViewGeometry.h
 * The two-view models of an uncalibrated pair and their motion decompositions, the building
 * blocks of TwoViewInitializer (monocular map start), usable on their own:
 *  - homography H_cur_ref (x_cur ~ H x_ref) by the normalised DLT, from >= 4 pixel pairs;
 *  - fundamental matrix F_cur_ref (x_cur^T F x_ref = 0) by the normalised 8-point algorithm,
 *    rank 2 enforced;
 *  - the 4 (R, t) of an essential matrix and the 8 (R, t) of a calibrated homography
 *    (Faugeras & Lustman 1988);
 *  - linear triangulation of one pair of normalised rays.
 * Convention everywhere: X_cur = R_cur_ref X_ref + t_cur_ref, optical frames (z forward).
 */
#include <Eigen/Core>

#include <vector>

namespace keygrid::sfm
{
/** One hypothesis of the motion of the current camera relative to the reference one; t has
 * unit norm (two views fix the translation only up to scale). */
struct RelativeMotion
{
	Eigen::Matrix3d R_cur_ref{Eigen::Matrix3d::Identity()};
	Eigen::Vector3d t_cur_ref{Eigen::Vector3d::Zero()};
};

/** Hartley's normalisation of a point set: the similarity T (x' = T x in homogeneous
 * coordinates) moving the centroid to the origin and scaling the mean distance to it to
 * sqrt(2), so that the DLT's design matrix has entries of order 1 (its conditioning otherwise
 * grows with the squared pixel coordinates, ~1e5 for a VGA image). Identity for < 2 points. */
Eigen::Matrix3d hartleyNormalisation(const std::vector<Eigen::Vector2d>& pts);

/** Normalised DLT: each pair gives the two independent rows of x_cur x (H x_ref) = 0 in the
 * 9 entries of H; h is the right singular vector of the smallest singular value, then
 * H = T_cur^-1 H_n T_ref. Returns false for < 4 pairs or a degenerate set (three collinear
 * points: the null space is more than one-dimensional). H is scaled to unit Frobenius norm. */
bool homographyDlt(
	const std::vector<Eigen::Vector2d>& x_ref, const std::vector<Eigen::Vector2d>& x_cur,
	Eigen::Matrix3d& H_cur_ref);

/** Normalised 8-point: each pair gives the row of x_cur^T F x_ref = 0 in the 9 entries of F,
 * solved as above; the closest rank-2 matrix (Frobenius) zeroes the smallest singular value
 * (every epipolar line then passes through one epipole), and F = T_cur^T F_n T_ref. Returns
 * false for < 8 pairs or a degenerate set. F is scaled to unit Frobenius norm. */
bool fundamentalEightPoint(
	const std::vector<Eigen::Vector2d>& x_ref, const std::vector<Eigen::Vector2d>& x_cur,
	Eigen::Matrix3d& F_cur_ref);

/** The four motions of E = [t]_x R (E = K^T F K, up to scale and sign). With E = U diag(1,1,0)
 * V^T (U, V proper rotations: E's sign is free), [t]_x = U Z U^T and R = U W V^T or U W^T V^T
 * with W = Rz(90 deg), t = +-u3 (the left null vector). Only one of them puts the points in
 * front of both cameras (cheirality). */
std::vector<RelativeMotion> decomposeEssential(const Eigen::Matrix3d& E);

/** The eight motions of a calibrated homography A = K^-1 H K (Faugeras & Lustman 1988; see the
 * derivation in the .cpp). Empty when two singular values of A coincide (relative gap below
 * minGap): all three equal is a pure rotation, two equal a motion along the plane normal; the
 * decomposition is then not unique. */
std::vector<RelativeMotion> decomposeHomography(const Eigen::Matrix3d& A, double minGap = 1e-5);

/** Linear (DLT) triangulation of the normalised rays ray_ref = (x, y, 1) and ray_cur with
 * P_ref = [I | 0], P_cur = [R | t]: the right null vector of the 4x4 system
 * x P^3 - P^1, y P^3 - P^2 of both views. False when the point is at infinity (parallel rays).
 * No cheirality test: the caller decides. */
bool triangulateRays(
	const Eigen::Vector3d& ray_ref, const Eigen::Vector3d& ray_cur, const RelativeMotion& m,
	Eigen::Vector3d& X_ref);

}  // namespace keygrid::sfm
