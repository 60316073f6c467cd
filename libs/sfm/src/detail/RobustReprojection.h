#pragma once
/** \file RobustReprojection.h
 * The reprojection residual of one observation with its Huber weight and its Jacobian with
 * respect to the point in the camera frame: shared by the pose solver and the bundle solver
 * (the residual of RgbdReprojectionCost.h, written for a point already in the camera frame).
 *
 * r = ((u_obs - u) s, (v_obs - v) s, (bf / d_obs - bf / z) s_d), the third only with depth,
 * with u = fx x / z + cx, v = fy y / z + cy. Huber with threshold delta on |r|:
 * rho(s) = s for s <= delta^2, 2 delta sqrt(s) - delta^2 beyond; rho'(s) re-weights the
 * residual block (Ceres' corrector for a loss whose second derivative is <= 0).
 */
#include <keygrid/sfm/RgbdReprojectionCost.h>

#include <Eigen/Core>
#include <cmath>

namespace keygrid::sfm::detail
{
/** Points at or behind this depth [m] cannot be evaluated. */
constexpr double kMinReprojectionDepth = 1e-6;

/** rho(s) and rho'(s) of the Huber loss with threshold delta (delta = 0: rho(s) = s). */
inline void huber(double s, double delta, double& rho, double& rho1)
{
	if (delta <= 0 || s <= delta * delta)
	{
		rho = s;
		rho1 = 1.0;
		return;
	}
	const double r = std::sqrt(s);
	rho = 2.0 * delta * r - delta * delta;
	rho1 = delta / r;
}

/** Residual r of a measurement (fields uv, invSigma, disparity, invSigmaDisparity) at the
 * camera-frame point pc; false behind the camera. */
template <class Measurement>
bool residualAt(const Eigen::Vector3d& pc, const Measurement& m, const PinholeIntrinsics& K, double bf, Eigen::Vector3d& r)
{
	if (pc.z() <= kMinReprojectionDepth) return false;
	const double iz = 1.0 / pc.z();
	r.x() = (m.uv.x() - (K.fx * pc.x() * iz + K.cx)) * m.invSigma;
	r.y() = (m.uv.y() - (K.fy * pc.y() * iz + K.cy)) * m.invSigma;
	r.z() = m.disparity > 0 ? (m.disparity - bf * iz) * m.invSigmaDisparity : 0.0;
	return true;
}

/** d r / d pc (third row zero without depth), pc in front of the camera. */
template <class Measurement>
Eigen::Matrix3d residualJacobian(const Eigen::Vector3d& pc, const Measurement& m, const PinholeIntrinsics& K, double bf)
{
	const double iz = 1.0 / pc.z(), e = -m.invSigma;
	Eigen::Matrix3d Jpc;
	Jpc << e * K.fx * iz, 0.0, -e * K.fx * pc.x() * iz * iz,  //
		0.0, e * K.fy * iz, -e * K.fy * pc.y() * iz * iz,  //
		0.0, 0.0, m.disparity > 0 ? m.invSigmaDisparity * bf * iz * iz : 0.0;
	return Jpc;
}

/** [a]x, the cross-product matrix. */
inline Eigen::Matrix3d skew(const Eigen::Vector3d& a)
{
	Eigen::Matrix3d S;
	S << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
	return S;
}

}  // namespace keygrid::sfm::detail
