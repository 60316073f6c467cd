#pragma once
/** \file RelativeSim3Error.h
 * The Sim(3) pose-graph error term (Ceres auto-diff functor). Needs Ceres headers: include it
 * only from code that links Ceres (libs/loop's Sim3PoseGraph.cpp, tests).
 */
#include <ceres/autodiff_cost_function.h>
#include <keygrid/loop/Sim3.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace keygrid::loop
{
/** Residual of one edge a -> b of the Sim(3) pose graph.
 *
 * Vertices are S_world_a = (s_a, R_a, t_a) and S_world_b, stored as t[3], a unit quaternion
 * q[4] in Eigen's (x, y, z, w) order (ceres::EigenQuaternionManifold) and the log-scale
 * sigma = log s [1]: s stays positive without bounds, and scale corrections compose additively,
 * so a loop's correction spreads evenly over its edges. The edge measures S_a_b = (s_m, R_m, t_m).
 * The misfit is the similarity
 *
 *     dS = S_a_b_measured^-1 S_world_a^-1 S_world_b = (s_d, R_d, t_d),
 *
 * the identity iff the estimate S_a_b^ = S_world_a^-1 S_world_b = (s^, R^, t^) equals the
 * measurement. Expanded with the rules of Sim3.h:
 *
 *     S_a_b^ = (s_b / s_a,  R_a^T R_b,  R_a^T (t_b - t_a) / s_a)
 *     dS     = (s^ / s_m,   R_m^T R^,   R_m^T (t^ - t_m) / s_m)
 *
 * Error, in b's frame and units (independent of the gauge):
 *     e_t = t_d                                         (units of b)
 *     e_q = 2 vec(q_d) = 2 sin(th/2) u ~= th u          (radians; q_d taken with w >= 0)
 *     e_s = log s_d = sigma_b - sigma_a - log s_m
 * log_Sim3(dS) = [V^-1 t_d; th u; log s_d] with V = I + O(th, log s_d), so e agrees with the
 * tangent-space error of ORB-SLAM's Sim(3) edges to first order at the optimum, without the
 * closed-form V^-1 and its small-angle branches. With Omega = U^T U (Cholesky), r = U e, Omega
 * ordered (x, y, z, rx, ry, rz, log s) as RelativePoseError's 6x6 one plus the scale.
 */
struct RelativeSim3Error
{
	using Matrix7d = Eigen::Matrix<double, 7, 7>;

	RelativeSim3Error(const Sim3& S_a_b_measured, const Matrix7d& sqrtInformation)
		: m_S_b_a_measured(Sim3{S_a_b_measured.q.normalized(), S_a_b_measured.t, S_a_b_measured.s}.inverse()),
		  m_logScaleMeasured(std::log(S_a_b_measured.s)),
		  m_sqrtInfo(sqrtInformation)
	{
	}

	template <typename T>
	bool operator()(
		const T* t_a_ptr, const T* q_a_ptr, const T* sigma_a, const T* t_b_ptr, const T* q_b_ptr, const T* sigma_b,
		T* r_ptr) const
	{
		using std::exp;
		const Sim3T<T> S_world_a{Eigen::Quaternion<T>(q_a_ptr), Eigen::Matrix<T, 3, 1>(t_a_ptr), exp(sigma_a[0])};
		const Sim3T<T> S_world_b{Eigen::Quaternion<T>(q_b_ptr), Eigen::Matrix<T, 3, 1>(t_b_ptr), exp(sigma_b[0])};
		const Sim3T<T> dS = m_S_b_a_measured.template cast<T>() * S_world_a.inverse() * S_world_b;

		Eigen::Quaternion<T> q_d = dS.q;
		if (q_d.w() < T(0)) q_d.coeffs() = -q_d.coeffs();

		Eigen::Map<Eigen::Matrix<T, 7, 1>> r(r_ptr);
		r.template head<3>() = dS.t;
		r.template segment<3>(3) = T(2.0) * q_d.vec();
		r(6) = sigma_b[0] - sigma_a[0] - T(m_logScaleMeasured);
		r.applyOnTheLeft(m_sqrtInfo.template cast<T>());
		return true;
	}

	/** Residuals 7; parameter blocks t_a (3), q_a (4), sigma_a (1), t_b (3), q_b (4), sigma_b (1). */
	static ceres::CostFunction* Create(const Sim3& S_a_b_measured, const Matrix7d& sqrtInformation)
	{
		return new ceres::AutoDiffCostFunction<RelativeSim3Error, 7, 3, 4, 1, 3, 4, 1>(
			new RelativeSim3Error(S_a_b_measured, sqrtInformation));
	}

	EIGEN_MAKE_ALIGNED_OPERATOR_NEW

   private:
	Sim3 m_S_b_a_measured;  //!< the measurement's inverse
	double m_logScaleMeasured;
	Matrix7d m_sqrtInfo;
};

}  // namespace keygrid::loop
