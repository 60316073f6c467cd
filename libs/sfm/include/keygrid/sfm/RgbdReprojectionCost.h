#pragma once
/** \file RgbdReprojectionCost.h
 * Reprojection residuals for RGB-D observations, as Ceres auto-diff functors.
 *
 * Frames: T_cam_world = (q_cam_world, t_cam_world) maps a world point p_world into the optical
 * camera frame: p_cam = R(q_cam_world) p_world + t_cam_world = (x, y, z).
 *
 * Pinhole prediction on the undistorted image:  u^ = fx x / z + cx,   v^ = fy y / z + cy.
 *
 * Depth enters as the disparity of a virtual stereo pair: a camera with baseline b would see the
 * point shifted by bf / z pixels (bf = fx * b). The third residual is the disparity error
 *     (bf / d_obs - bf / z) / sigma_disparity,
 * an inverse-depth error scaled to pixels; its metric standard deviation is
 * sigma_z = sigma_disparity z^2 / bf, growing as z^2 like the noise of structured-light sensors
 * (Kinect: about 1.4 mm z^2, z in m).
 *
 * The (u, v) residuals are divided by sigma_level = scaleFactor^level (keypoints from coarser
 * pyramid levels are less precisely located); the depth residual is not: the measured depth
 * does not depend on the level the keypoint was detected at. (ORB-SLAM2's virtual right
 * coordinate u_obs - bf / d_obs, divided by sigma_level, re-counts the u error and weights
 * the depth of a coarse-level keypoint far less than the sensor's noise warrants, which leaves
 * the pose free along the rotation/translation ambiguity of narrow-field reprojection.) The
 * caller adds the robust (Huber) loss.
 */
#include <keygrid/core/PinholeIntrinsics.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace keygrid::sfm
{
/** The undistorted image's pinhole model (core/PinholeIntrinsics.h: why it is apart from
 * core::RgbdCamera); core::RgbdCamera::pinhole() converts a camera. */
using PinholeIntrinsics = core::PinholeIntrinsics;

/** Pixel (and virtual right pixel) of p_world seen from T_cam_world; returns false behind. */
template <typename T>
bool projectRgbd(
	const T* q_cam_world, const T* t_cam_world, const T* p_world, const PinholeIntrinsics& K,
	double bf, T& u, T& v, T& ur)
{
	const Eigen::Map<const Eigen::Quaternion<T>> q(q_cam_world);
	const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(t_cam_world);
	const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p(p_world);
	const Eigen::Matrix<T, 3, 1> pc = q * p + t;
	if (pc.z() <= T(1e-6)) return false;
	const T iz = T(1.0) / pc.z();
	u = T(K.fx) * pc.x() * iz + T(K.cx);
	v = T(K.fy) * pc.y() * iz + T(K.cy);
	ur = u - T(bf) * iz;
	return true;
}

/** 2 residuals (u, v): keypoints without valid depth. Parameters: q_cam_world[4] (x,y,z,w),
 * t_cam_world[3], p_world[3]. */
struct MonoReprojectionCost
{
	MonoReprojectionCost(const Eigen::Vector2d& uv, double invSigma, const PinholeIntrinsics& K)
		: m_uv(uv), m_invSigma(invSigma), m_K(K)
	{
	}
	template <typename T>
	bool operator()(const T* q, const T* t, const T* p, T* r) const
	{
		T u, v, ur;
		if (!projectRgbd(q, t, p, m_K, 0.0, u, v, ur)) return false;
		r[0] = (T(m_uv.x()) - u) * T(m_invSigma);
		r[1] = (T(m_uv.y()) - v) * T(m_invSigma);
		return true;
	}
	Eigen::Vector2d m_uv;
	double m_invSigma;
	PinholeIntrinsics m_K;
};

/** 3 residuals (u, v, disparity): keypoints with valid depth d_obs. Same parameters.
 * invSigma = 1 / sigma_level, invSigmaDisparity = 1 / sigma_disparity [1/px]. */
struct RgbdReprojectionCost
{
	RgbdReprojectionCost(
		const Eigen::Vector2d& uv, double depth, double bf, double invSigma, double invSigmaDisparity,
		const PinholeIntrinsics& K)
		: m_uv(uv), m_disparity(bf / depth), m_bf(bf), m_invSigma(invSigma), m_invSigmaDisparity(invSigmaDisparity), m_K(K)
	{
	}
	template <typename T>
	bool operator()(const T* q, const T* t, const T* p, T* r) const
	{
		T u, v, ur;
		if (!projectRgbd(q, t, p, m_K, m_bf, u, v, ur)) return false;
		r[0] = (T(m_uv.x()) - u) * T(m_invSigma);
		r[1] = (T(m_uv.y()) - v) * T(m_invSigma);
		r[2] = (T(m_disparity) - (u - ur)) * T(m_invSigmaDisparity);  // u - ur = bf / z
		return true;
	}
	Eigen::Vector2d m_uv;
	double m_disparity, m_bf, m_invSigma, m_invSigmaDisparity;
	PinholeIntrinsics m_K;
};

/** Reprojection residuals with hand-written Jacobians, for bundle adjustment (same model and
 * parameters as RgbdReprojectionCost / MonoReprojectionCost). Always 3 residuals: without
 * depth the third one is identically 0 (zero Jacobian row), so every residual block of a BA
 * problem has the same shape (3 residuals; q: 3 tangent dims, t: 3, p: 3) and Ceres can use
 * its fixed-size Schur eliminator.
 *
 * With q = (v, w) (v = x,y,z), Eigen evaluates q * p = p + 2w (v x p) + 2 v x (v x p); the
 * Jacobians below are those of this polynomial (exact also for a not quite unit q, like
 * autodiff of the templated costs):
 *   d pc / dw = 2 (v x p)
 *   d pc / dv = -2w [p]x + 2 ((v.p) I + v p^T - 2 p v^T)
 *   d pc / dp = I + 2w [v]x + 2 [v]x^2   (= R(q) for a unit q)
 *   d pc / dt = I
 * and with (x, y, z) = pc, e = -invSigma:
 *   d r0 / d pc = e (fx / z, 0, -fx x / z^2)
 *   d r1 / d pc = e (0, fy / z, -fy y / z^2)
 *   d r2 / d pc = (0, 0, invSigmaDisparity bf / z^2)     (only with depth)
 */
struct AnalyticReprojectionCost
{
	/** Observation with depth (3 residuals); `depth` <= 0 gives a mono one (third residual 0). */
	AnalyticReprojectionCost(
		const Eigen::Vector2d& uv, double depth, double bf, double invSigma, double invSigmaDisparity,
		const PinholeIntrinsics& K)
		: m_uv(uv),
		  m_disparity(depth > 0 ? bf / depth : 0.0),
		  m_bf(bf),
		  m_invSigma(invSigma),
		  m_invSigmaDisparity(invSigmaDisparity),
		  m_rgbd(depth > 0),
		  m_K(K)
	{
	}

	/** Residuals r[3] and, for each non-null pointer, the row-major Jacobians Jq (3x4, w.r.t.
	 * q_cam_world as x,y,z,w), Jt (3x3), Jp (3x3). False if the point is behind the camera. */
	bool evaluate(const double* qv, const double* tv, const double* pv, double* r, double* Jq, double* Jt, double* Jp) const
	{
		using M3 = Eigen::Matrix3d;
		const Eigen::Map<const Eigen::Vector3d> v(qv), t(tv), p(pv);
		const double w = qv[3];
		const Eigen::Vector3d vxp = v.cross(p);
		const Eigen::Vector3d pc = p + 2.0 * w * vxp + 2.0 * v.cross(vxp) + t;
		if (pc.z() <= 1e-6) return false;
		const double iz = 1.0 / pc.z();
		const double u = m_K.fx * pc.x() * iz + m_K.cx, vv = m_K.fy * pc.y() * iz + m_K.cy;
		r[0] = (m_uv.x() - u) * m_invSigma;
		r[1] = (m_uv.y() - vv) * m_invSigma;
		r[2] = m_rgbd ? (m_disparity - m_bf * iz) * m_invSigmaDisparity : 0.0;
		if (!Jq && !Jt && !Jp) return true;
		// d r / d pc (3x3, third row zero without depth).
		const double e = -m_invSigma;
		Eigen::Matrix3d Jpc;
		Jpc << e * m_K.fx * iz, 0.0, -e * m_K.fx * pc.x() * iz * iz,  //
			0.0, e * m_K.fy * iz, -e * m_K.fy * pc.y() * iz * iz,  //
			0.0, 0.0, 0.0;
		if (m_rgbd) Jpc(2, 2) = m_invSigmaDisparity * m_bf * iz * iz;
		const auto skew = [](const Eigen::Vector3d& a)
		{
			M3 S;
			S << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
			return S;
		};
		using Row33 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
		if (Jt) Eigen::Map<Row33>{Jt} = Jpc;
		if (Jp)
		{
			const M3 V = skew(v);
			Eigen::Map<Row33>{Jp} = Jpc * (M3::Identity() + 2.0 * w * V + 2.0 * V * V);
		}
		if (Jq)
		{
			Eigen::Matrix<double, 3, 4> dq;
			dq.leftCols<3>() = -2.0 * w * skew(p) + 2.0 * (v.dot(p) * M3::Identity() + v * p.transpose() - 2.0 * p * v.transpose());
			dq.col(3) = 2.0 * vxp;
			Eigen::Map<Eigen::Matrix<double, 3, 4, Eigen::RowMajor>>{Jq} = Jpc * dq;
		}
		return true;
	}

	bool hasDepth() const { return m_rgbd; }

	Eigen::Vector2d m_uv;
	double m_disparity, m_bf, m_invSigma, m_invSigmaDisparity;
	bool m_rgbd;
	PinholeIntrinsics m_K;
};

}  // namespace keygrid::sfm
