#pragma once
/** \file TumTrajectory.h
 * TUM trajectory files: one pose per line, `t tx ty tz qx qy qz qw`, the pose T_world_cam of the
 * camera's optical frame.
 */
#include <keygrid/core/TumText.h>
#include <mrpt/poses/CPose3D.h>

#include <string>
#include <vector>

namespace keygrid::core
{
struct StampedPose
{
	double t{0};  //!< timestamp [s]
	mrpt::poses::CPose3D T_world_cam;
};
using Trajectory = std::vector<StampedPose>;

struct TrajectoryReadOptions
{
	/** Skip malformed lines (reported in `issues`) instead of throwing (Default: false) */
	bool skipBadLines{false};
	/** Largest accepted | |q| - 1 | before a quaternion is called malformed (Default: 1e-3) */
	double quaternionNormTolerance{1e-3};
};

/** Reads a TUM trajectory. Quaternions are renormalised; the result is sorted by time.
 * Malformed lines (wrong field count, non-numbers, bad quaternion, repeated timestamp) throw
 * std::runtime_error naming file:line, or are skipped and listed in *issues when
 * opts.skipBadLines. */
Trajectory readTumTrajectory(
	const std::string& path, const TrajectoryReadOptions& opts = {},
	std::vector<TextLineIssue>* issues = nullptr);

/** Writes a TUM trajectory (with a '#' header line). Throws on I/O failure. */
void writeTumTrajectory(
	const std::string& path, const Trajectory& traj, const std::string& header = "");

/** Formats one TUM line (no newline). */
std::string tumLine(const StampedPose& p);

}  // namespace keygrid::core
