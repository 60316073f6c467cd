#include "IniHelpers.h"

#include <keygrid/core/VectorAngle.h>
#include <keygrid/sim/CameraTrajectory.h>
#include <mrpt/math/CMatrixFixed.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace keygrid::sim
{
namespace
{
Eigen::Vector3d dirOf(const Waypoint& w) { return (w.target - w.eye).normalized(); }

// Cubic Hermite on [0, 1] with end velocities already scaled by the segment duration.
Eigen::Vector3d hermite(
	const Eigen::Vector3d& p0, const Eigen::Vector3d& m0, const Eigen::Vector3d& p1,
	const Eigen::Vector3d& m1, double s)
{
	const double s2 = s * s, s3 = s2 * s;
	return (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * p1 +
		   (s3 - s2) * m1;
}
}  // namespace

Eigen::Matrix3d CameraTrajectory::lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target)
{
	const Eigen::Vector3d fwd = target - eye;
	if (fwd.norm() < 1e-9) throw std::invalid_argument("camera eye and look-at point coincide");
	const Eigen::Vector3d z = fwd.normalized();
	const Eigen::Vector3d xRaw = z.cross(Eigen::Vector3d::UnitZ());
	if (xRaw.norm() < 1e-3)
		throw std::invalid_argument(
			"camera looks (nearly) straight up or down: orientation undefined");
	const Eigen::Vector3d x = xRaw.normalized();
	const Eigen::Vector3d y = z.cross(x);
	Eigen::Matrix3d R;
	R.col(0) = x;
	R.col(1) = y;
	R.col(2) = z;
	return R;
}

CameraTrajectory::CameraTrajectory(
	std::vector<Waypoint> wps, double duration, const CameraTrajectoryOptions& opts)
	: m_wps(std::move(wps)), m_duration(duration), m_opts(opts)
{
	if (m_wps.empty()) throw std::invalid_argument("camera trajectory has no waypoint (wp_00)");
	if (!(duration > 0)) throw std::invalid_argument("camera trajectory duration must be > 0");
	if (!(opts.refSpeed > 0 && opts.refTurnRateDeg > 0))
		throw std::invalid_argument("ref_speed and ref_turn_rate_deg must be > 0");
	for (const auto& w : m_wps) lookAt(w.eye, w.target);  // validates every waypoint
	const std::size_t n = m_wps.size();
	const std::size_t nSeg = n == 1 ? 0 : (m_opts.loop ? n : n - 1);
	std::vector<double> weight(nSeg);
	double sum = 0;
	for (std::size_t i = 0; i < nSeg; i++)
	{
		const Waypoint& a = m_wps[i];
		const Waypoint& b = m_wps[(i + 1) % n];
		const double len = (b.eye - a.eye).norm();
		const double turn = core::angleBetween(dirOf(a), dirOf(b));
		weight[i] =
			std::max({len / opts.refSpeed, turn / (opts.refTurnRateDeg * M_PI / 180.0), 1e-6});
		sum += weight[i];
	}
	m_knots.assign(1, 0.0);
	for (std::size_t i = 0; i < nSeg; i++)
		m_knots.push_back(m_knots.back() + weight[i] / sum * duration);
	if (nSeg) m_knots.back() = duration;
}

Waypoint CameraTrajectory::waypointAt(double t) const
{
	if (m_wps.empty())
		throw std::logic_error("the scene has no camera trajectory ([trajectory] section)");
	const std::size_t n = m_wps.size();
	const std::size_t nSeg = m_knots.size() - 1;
	if (nSeg == 0) return m_wps.front();
	if (m_opts.loop)
	{
		t = std::fmod(t, m_duration);
		if (t < 0) t += m_duration;
	}
	else
		t = std::clamp(t, 0.0, m_duration);
	const std::size_t seg = std::min<std::size_t>(
		nSeg - 1, static_cast<std::size_t>(
					  std::upper_bound(m_knots.begin(), m_knots.end(), t) - m_knots.begin()) -
					  1);
	const double dt = m_knots[seg + 1] - m_knots[seg];
	const double s = (t - m_knots[seg]) / dt;
	auto segDur = [&](long j) {
		// Duration of segment j (wrapped for loops; 0 outside an open path).
		if (m_opts.loop)
			j = (j % static_cast<long>(nSeg) + static_cast<long>(nSeg)) % static_cast<long>(nSeg);
		else if (j < 0 || j >= static_cast<long>(nSeg))
			return 0.0;
		return m_knots[j + 1] - m_knots[j];
	};
	// Velocity at waypoint k (non-uniform Catmull-Rom); open ends start and stop at rest.
	auto velocity = [&](std::size_t k, auto member) -> Eigen::Vector3d {
		if (!m_opts.loop && (k == 0 || k == n - 1)) return Eigen::Vector3d::Zero();
		const auto& prev = m_wps[(k + n - 1) % n];
		const auto& next = m_wps[(k + 1) % n];
		const double span = segDur(static_cast<long>(k) - 1) + segDur(static_cast<long>(k));
		return (next.*member - prev.*member) / span;
	};
	const std::size_t k0 = seg, k1 = (seg + 1) % n;
	Waypoint out;
	for (auto member : {&Waypoint::eye, &Waypoint::target})
	{
		const Eigen::Vector3d m0 = velocity(k0, member) * dt, m1 = velocity(k1, member) * dt;
		out.*member = hermite(m_wps[k0].*member, m0, m_wps[k1].*member, m1, s);
	}
	return out;
}

mrpt::poses::CPose3D CameraTrajectory::poseAt(double t) const
{
	const Waypoint w = waypointAt(t);
	const Eigen::Matrix3d R = lookAt(w.eye, w.target);
	mrpt::math::CMatrixDouble33 rot;
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++) rot(r, c) = R(r, c);
	return mrpt::poses::CPose3D(
		rot, mrpt::math::CVectorFixedDouble<3>({w.eye.x(), w.eye.y(), w.eye.z()}));
}

void CameraTrajectory::maxSpeeds(double rateHz, double& linear, double& angular) const
{
	linear = angular = 0;
	if (empty()) return;
	const double dt = 1.0 / rateHz;
	mrpt::poses::CPose3D prev = poseAt(0);
	for (double t = dt; t <= m_duration + 1e-9; t += dt)
	{
		const mrpt::poses::CPose3D cur = poseAt(t);
		const mrpt::poses::CPose3D rel = cur - prev;
		linear = std::max(linear, rel.translation().norm() / dt);
		const auto R = rel.getRotationMatrix();
		const double c = std::clamp((R(0, 0) + R(1, 1) + R(2, 2) - 1.0) / 2.0, -1.0, 1.0);
		angular = std::max(angular, std::acos(c) / dt);
		prev = cur;
	}
}

CameraTrajectory CameraTrajectory::loadFromConfigFile(
	const mrpt::config::CConfigFileBase& cfg, const std::string& s, double duration)
{
	CameraTrajectoryOptions o;
	o.loop = ini::readBool(cfg, s, "loop", o.loop);
	o.refSpeed = ini::readDouble(cfg, s, "ref_speed", o.refSpeed, 1e-3, 100);
	o.refTurnRateDeg = ini::readDouble(cfg, s, "ref_turn_rate_deg", o.refTurnRateDeg, 1e-3, 3600);
	std::vector<Waypoint> wps;
	for (int i = 0; i < 1000; i++)
	{
		char key[16];
		std::snprintf(key, sizeof(key), "wp_%02d", i);
		const std::string v = ini::raw(cfg, s, key);
		if (v.empty()) break;
		const auto x = ini::numbers(s, key, v);
		Waypoint w;
		if (x.size() == 6)
		{
			w.eye = {x[0], x[1], x[2]};
			w.target = {x[3], x[4], x[5]};
		}
		else if (x.size() == 5)
		{
			const double yaw = x[3] * M_PI / 180, pitch = x[4] * M_PI / 180;
			w.eye = {x[0], x[1], x[2]};
			w.target = w.eye + Eigen::Vector3d(
								   std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw),
								   std::sin(pitch));
		}
		else
			ini::fail(s, key, v, "expected 'ex ey ez tx ty tz' or 'ex ey ez yaw_deg pitch_deg'");
		if ((w.target - w.eye).norm() < 1e-9)
			ini::fail(s, key, v, "eye and look-at point coincide");
		wps.push_back(w);
	}
	if (wps.empty()) throw std::invalid_argument("[" + s + "] has no waypoint wp_00");
	try
	{
		return CameraTrajectory(std::move(wps), duration, o);
	}
	catch (const std::invalid_argument& e)
	{
		throw std::invalid_argument("[" + s + "] " + e.what());
	}
}

}  // namespace keygrid::sim
