#pragma once
/** \file RelativePoseError.h
 * The pose-graph error term (Ceres auto-diff functor). Needs Ceres headers: include it only
 * from code that links Ceres (libs/loop's PoseGraph.cpp, tests).
 */
#include <ceres/autodiff_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace keygrid::loop
{
/** Residual of one edge a -> b of the pose graph.
 *
 * Vertices are T_world_a = (R_a, p_a) and T_world_b = (R_b, p_b), stored as p[3] and a unit
 * quaternion q[4] in Eigen's (x, y, z, w) order (ceres::EigenQuaternionManifold). The edge
 * measures T_a_b = (q_ab_measured, p_ab_measured). The estimate of the same relative pose is
 *
 *     T_a_b^ = T_world_a^-1 T_world_b :   q_ab^ = q_a^-1 q_b,   p_ab^ = R_a^T (p_b - p_a).
 *
 * Errors, both expressed in a local frame so that they do not depend on the gauge:
 *     e_p = p_ab^ - p_ab_measured                                  (frame a, metres)
 *     dq  = q_ab_measured^-1 q_ab^ = [cos(th/2), sin(th/2) u],     (frame b)
 *     e_q = 2 vec(dq) = 2 sin(th/2) u ~= th u                      (radians, small angles)
 * dq is taken with w >= 0 (q and -q are the same rotation) so e_q is continuous at identity.
 * With the information matrix Omega = U^T U (Cholesky, U upper triangular), the residual is
 *     r = U [e_p; e_q]   so that   |r|^2 = e^T Omega e,
 * with Omega ordered (x, y, z, rx, ry, rz) as in g2o's EDGE_SE3:QUAT and Ceres' pose_graph_3d.
 */
struct RelativePoseError
{
	RelativePoseError(
		const Eigen::Quaterniond& q_ab_measured, const Eigen::Vector3d& p_ab_measured,
		const Eigen::Matrix<double, 6, 6>& sqrtInformation)
		: m_q_ab_measured(q_ab_measured.normalized()), m_p_ab_measured(p_ab_measured), m_sqrtInfo(sqrtInformation)
	{
	}

	template <typename T>
	bool operator()(const T* p_a_ptr, const T* q_a_ptr, const T* p_b_ptr, const T* q_b_ptr, T* r_ptr) const
	{
		const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_a(p_a_ptr), p_b(p_b_ptr);
		const Eigen::Map<const Eigen::Quaternion<T>> q_a(q_a_ptr), q_b(q_b_ptr);
		const Eigen::Quaternion<T> q_a_inv = q_a.conjugate();
		const Eigen::Quaternion<T> q_ab = q_a_inv * q_b;
		const Eigen::Matrix<T, 3, 1> p_ab = q_a_inv * (p_b - p_a);

		Eigen::Quaternion<T> dq = m_q_ab_measured.template cast<T>().conjugate() * q_ab;
		if (dq.w() < T(0)) dq.coeffs() = -dq.coeffs();

		Eigen::Map<Eigen::Matrix<T, 6, 1>> r(r_ptr);
		r.template head<3>() = p_ab - m_p_ab_measured.template cast<T>();
		r.template tail<3>() = T(2.0) * dq.vec();
		r.applyOnTheLeft(m_sqrtInfo.template cast<T>());
		return true;
	}

	/** Residuals 6; parameter blocks p_a (3), q_a (4), p_b (3), q_b (4). */
	static ceres::CostFunction* Create(
		const Eigen::Quaterniond& q_ab_measured, const Eigen::Vector3d& p_ab_measured,
		const Eigen::Matrix<double, 6, 6>& sqrtInformation)
	{
		return new ceres::AutoDiffCostFunction<RelativePoseError, 6, 3, 4, 3, 4>(
			new RelativePoseError(q_ab_measured, p_ab_measured, sqrtInformation));
	}

	EIGEN_MAKE_ALIGNED_OPERATOR_NEW

   private:
	Eigen::Quaterniond m_q_ab_measured;
	Eigen::Vector3d m_p_ab_measured;
	Eigen::Matrix<double, 6, 6> m_sqrtInfo;
};

}  // namespace keygrid::loop
