#include <keygrid/sfm/RollingShutter.h>

#include <Eigen/Geometry>
#include <stdexcept>
#include <string>

namespace keygrid::sfm
{
CameraRates ratesFromRelativePose(const mrpt::poses::CPose3D& T_a_b, double dt)
{
	if (!(dt > 0)) throw std::invalid_argument("ratesFromRelativePose: dt = " + std::to_string(dt) + " (must be > 0)");
	const auto Rm = T_a_b.getRotationMatrix();
	Eigen::Matrix3d R;
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++) R(i, j) = Rm(i, j);
	const Eigen::AngleAxisd aa(R);
	CameraRates r;
	r.omega = aa.axis() * (aa.angle() / dt);
	r.velocity = Eigen::Vector3d(T_a_b.x(), T_a_b.y(), T_a_b.z()) / dt;
	return r;
}

RollingShutterCompensator::RollingShutterCompensator(const FrameFeatures& f, double readout)
	: m_measured(f.undistorted), m_depth(f.depth)
{
	if (!(readout >= 0)) throw std::invalid_argument("RollingShutterCompensator: readout = " + std::to_string(readout) + " s (must be >= 0)");
	m_rowTime.reserve(f.size());
	const double h = f.camera.height > 0 ? static_cast<double>(f.camera.height) : 1.0;
	// The capture time follows the raw (distorted) row the sensor read the keypoint from.
	for (const auto& kp : f.keypoints) m_rowTime.push_back(static_cast<float>(rowTimeOffset(kp.pt.y, h, readout)));
}

void RollingShutterCompensator::apply(FrameFeatures& f, const CameraRates& rates, const PinholeIntrinsics& K) const
{
	if (f.size() != m_measured.size())
		throw std::invalid_argument("RollingShutterCompensator::apply: " + std::to_string(f.size()) + " keypoints, " +
									std::to_string(m_measured.size()) + " measured");
	for (std::size_t i = 0; i < m_measured.size(); i++)
	{
		const double tau = m_rowTime[i];
		const float d = m_depth[i];
		f.undistorted[i] = m_measured[i];
		f.depth[i] = d;
		if (tau == 0.0) continue;
		const Eigen::Vector3d bearing = K.ray(m_measured[i].x, m_measured[i].y);
		const Eigen::Vector3d rot = tau * rates.omega;
		const double angle = rot.norm();
		const Eigen::Matrix3d R = angle > 0 ? Eigen::AngleAxisd(angle, rot / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
		// P_t = R P_(t+tau) + tau v (with depth); the bearing R b without.
		const Eigen::Vector3d p = d > 0 ? Eigen::Vector3d(R * (bearing * d) + tau * rates.velocity) : Eigen::Vector3d(R * bearing);
		if (p.z() <= 0) continue;  // not for the rates of a real camera; keeps the measurement
		f.undistorted[i] = {static_cast<float>(K.fx * p.x() / p.z() + K.cx), static_cast<float>(K.fy * p.y() / p.z() + K.cy)};
		if (d > 0) f.depth[i] = static_cast<float>(p.z());
	}
	f.buildGrid(f.gridCellSize());
}

}  // namespace keygrid::sfm
