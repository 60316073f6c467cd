#pragma once
/** \file Alignment.h
 * Closed-form least-squares alignment of two point sets (Horn 1987 / Umeyama 1991).
 */
#include <Eigen/Core>
#include <mrpt/poses/CPose3D.h>

#include <vector>

namespace keygrid::eval
{
/** y ~= s * R * x + t */
struct Similarity3
{
	Eigen::Matrix3d R{Eigen::Matrix3d::Identity()};
	Eigen::Vector3d t{Eigen::Vector3d::Zero()};
	double s{1.0};

	Eigen::Vector3d apply(const Eigen::Vector3d& x) const { return s * (R * x) + t; }
};

/** Finds (R, t[, s]) minimising sum_i |y_i - (s R x_i + t)|^2.
 *
 * With centroids mx, my and the cross-covariance S = 1/n sum (y_i - my)(x_i - mx)^T = U D V^T,
 * R = U W V^T with W = diag(1, 1, sign(det(U) det(V))) (a rotation, never a reflection),
 * s = tr(D W) / var_x when withScale (else 1), and t = my - s R mx.
 * Requires n >= 3 points (throws std::invalid_argument otherwise). Degenerate sets are
 * handled: for collinear points the rotation about the line is one of the optima, for
 * coincident points R = I. */
Similarity3 alignPointSets(
	const std::vector<Eigen::Vector3d>& x, const std::vector<Eigen::Vector3d>& y, bool withScale);

/** The rotation R minimising sum_k |Ry_k - R Rx_k|_F^2 (chordal L2 mean of Ry_k Rx_k^T): the
 * polar factor U W V^T of M = sum_k Ry_k Rx_k^T = U D V^T, W = diag(1, 1, sign(det(U V^T))).
 * Throws std::invalid_argument when the sizes differ or there is none. */
Eigen::Matrix3d chordalMeanRotation(const std::vector<Eigen::Matrix3d>& Rx, const std::vector<Eigen::Matrix3d>& Ry);

/** Rigid alignment of two sets of poses (camera frames), T_y_x: R = chordalMeanRotation of
 * their orientations, t = mean_k (p_y_k - R p_x_k), s = 1. Unlike alignPointSets it is well
 * posed when the positions barely spread (a camera turning on the spot), because the
 * orientations fix the rotation. Needs at least one pair. */
Similarity3 alignPoses(const std::vector<mrpt::poses::CPose3D>& x, const std::vector<mrpt::poses::CPose3D>& y);

/** The rotation and translation of an alignment as a pose (the scale dropped): T_y_x. */
mrpt::poses::CPose3D rigidPose(const Similarity3& a);

}  // namespace keygrid::eval
