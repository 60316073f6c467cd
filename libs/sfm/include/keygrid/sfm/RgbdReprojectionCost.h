#pragma once
/** \file RgbdReprojectionCost.h
 * Reprojection residuals for RGB-D observations, as Ceres auto-diff functors.
 *
 * Frames: T_cam_world = (q_cam_world, t_cam_world) maps a world point p_world into the optical
 * camera frame: p_cam = R(q_cam_world) p_world + t_cam_world = (x, y, z).
 *
 * Pinhole prediction on the undistorted image:  u^ = fx x / z + cx,   v^ = fy y / z + cy.
 *
 * Depth enters as a virtual stereo pair (the RGB-D model of ORB-SLAM2): a camera with baseline
 * b would see the point at u_r = u - fx b / z. With bf = fx * b the measured right coordinate is
 * u_r = u_obs - bf / d_obs and the predicted one u^_r = u^ - bf / z, so the third residual is
 *     (u_obs - u^) - bf (1/d_obs - 1/z),
 * an inverse-depth error scaled to pixels. Its metric standard deviation grows as z^2 / bf,
 * which matches the disparity noise of structured-light sensors (Kinect).
 *
 * Residuals are divided by sigma_level = scaleFactor^level (keypoints from coarser pyramid
 * levels are less precise); the caller adds the robust (Huber) loss.
 */
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace keygrid::sfm
{
struct PinholeIntrinsics
{
	double fx{525}, fy{525}, cx{319.5}, cy{239.5};
};

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

/** 3 residuals (u, v, u_r): keypoints with valid depth d_obs. Same parameters. */
struct RgbdReprojectionCost
{
	RgbdReprojectionCost(
		const Eigen::Vector2d& uv, double depth, double bf, double invSigma, const PinholeIntrinsics& K)
		: m_uv(uv), m_ur(uv.x() - bf / depth), m_bf(bf), m_invSigma(invSigma), m_K(K)
	{
	}
	template <typename T>
	bool operator()(const T* q, const T* t, const T* p, T* r) const
	{
		T u, v, ur;
		if (!projectRgbd(q, t, p, m_K, m_bf, u, v, ur)) return false;
		r[0] = (T(m_uv.x()) - u) * T(m_invSigma);
		r[1] = (T(m_uv.y()) - v) * T(m_invSigma);
		r[2] = (T(m_ur) - ur) * T(m_invSigma);
		return true;
	}
	Eigen::Vector2d m_uv;
	double m_ur, m_bf, m_invSigma;
	PinholeIntrinsics m_K;
};

/** Wraps a 3-parameter-block cost so that the point is a constant (pose-only problems). */
template <typename Cost>
struct FixedPointCost
{
	FixedPointCost(const Cost& c, const Eigen::Vector3d& p_world) : m_cost(c), m_p(p_world) {}
	template <typename T>
	bool operator()(const T* q, const T* t, T* r) const
	{
		const T p[3] = {T(m_p.x()), T(m_p.y()), T(m_p.z())};
		return m_cost(q, t, p, r);
	}
	Cost m_cost;
	Eigen::Vector3d m_p;
};

}  // namespace keygrid::sfm
