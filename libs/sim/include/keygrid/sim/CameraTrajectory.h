#pragma once
/** \file CameraTrajectory.h
 * A smooth camera path through waypoints (eye position + look-at point, world frame, z up).
 *
 * Segment i (waypoint i -> i+1) gets a duration proportional to
 * max(length_i / v_ref, turn_i / w_ref), scaled so the whole path lasts the requested time:
 * long or sharply turning segments get more time, so speed stays roughly uniform.
 * Eye and look-at point are interpolated by cubic Hermite splines whose tangents are the
 * non-uniform Catmull-Rom velocities (P_{i+1} - P_{i-1}) / (dt_{i-1} + dt_i): velocity is
 * continuous in time across waypoints. Open paths start and end at rest; closed paths (loop)
 * wrap around, so the camera returns exactly to its start.
 * Orientation: optical z towards the look-at point, optical x = z x up_world (right), y = z x x.
 */
#include <Eigen/Core>
#include <mrpt/poses/CPose3D.h>

#include <string>
#include <vector>

namespace mrpt::config
{
class CConfigFileBase;
}

namespace keygrid::sim
{
struct Waypoint
{
	Eigen::Vector3d eye{0, 0, 1};     //!< camera centre [m], world frame
	Eigen::Vector3d target{1, 0, 1};  //!< point looked at [m], world frame
};

struct CameraTrajectoryOptions
{
	/** Closed path: after the last waypoint the camera returns to the first (Default: false) */
	bool loop{false};
	/** Reference speeds that apportion time among segments (Default: 0.4 m/s, 40 deg/s) */
	double refSpeed{0.4};
	double refTurnRateDeg{40.0};
};

class CameraTrajectory
{
   public:
	CameraTrajectory() = default;
	/** Throws std::invalid_argument if waypoints is empty, duration <= 0, a look direction is
	 * (near) vertical or an eye coincides with its target. */
	CameraTrajectory(
		std::vector<Waypoint> waypoints, double duration, const CameraTrajectoryOptions& opts = {});

	/** Reads [section]: `loop`, `ref_speed`, `ref_turn_rate_deg` and waypoints `wp_00`, `wp_01`,
	 * ... (consecutive from 00) as "ex ey ez tx ty tz" (eye + look-at) or
	 * "ex ey ez yaw_deg pitch_deg" (yaw about world z from +x, pitch up). */
	static CameraTrajectory loadFromConfigFile(
		const mrpt::config::CConfigFileBase& cfg, const std::string& section, double duration);

	/** Pose of the optical frame (x right, y down, z forward) in the world at time t [s]
	 * (clamped to [0, duration]; a loop is periodic). Throws std::logic_error when empty(). */
	mrpt::poses::CPose3D poseAt(double t) const;
	/** Eye and look-at point at time t. */
	Waypoint waypointAt(double t) const;

	/** True for a default-constructed trajectory (a scene without [trajectory]). */
	bool empty() const { return m_wps.empty(); }
	double duration() const { return m_duration; }
	const std::vector<Waypoint>& waypoints() const { return m_wps; }
	const CameraTrajectoryOptions& options() const { return m_opts; }
	/** Start time of each segment (size = number of segments + 1). */
	const std::vector<double>& knotTimes() const { return m_knots; }

	/** Largest linear [m/s] and angular [rad/s] speed over samples at `rateHz`. */
	void maxSpeeds(double rateHz, double& linear, double& angular) const;

	/** Rotation world <- optical for an eye looking at target with world z up. */
	static Eigen::Matrix3d lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target);

   private:
	std::vector<Waypoint> m_wps;
	std::vector<double> m_knots;
	double m_duration{1.0};
	CameraTrajectoryOptions m_opts;
};

}  // namespace keygrid::sim
