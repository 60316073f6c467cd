#pragma once
/** \file SlamRunHelpers.h
 * Inputs and process helpers for the tests that run keygrid-slam as a user would: small
 * textured RGB-D frames, rawlogs made of them, a fast configuration, and running the tool
 * while keeping its raw wait status (to tell an exit from a death by signal).
 */
#include <keygrid/core/Frame.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include <string>
#include <vector>

namespace keygrid::test
{
/** Camera of the helper frames: 160x120, fx = fy = 130 px, depth unit 1 mm. */
core::RgbdCamera smallCamera();

/** Frame `i` of a camera panning right over a blocky random texture (1 px per frame), at a
 * constant depth of `depthM` metres (0 = all-zero depth). Deterministic for given arguments. */
core::Frame texturedFrame(std::size_t i, float depthM = 2.0f);

/** The observation makeRgbdObservation() builds from texturedFrame(i). */
mrpt::obs::CObservation3DRangeScan::Ptr texturedObservation(std::size_t i, float depthM = 2.0f);

/** Writes observations to `path` with RawlogWriter (gzip level `compression`, 0 = none). */
void writeRawlog(
	const std::string& path, const std::vector<mrpt::obs::CObservation3DRangeScan::Ptr>& obs,
	int compression = 0);

/** Writes a fast keygrid-slam configuration (ORB 500 features, no global refinement, no loop
 * closing; with `maps`, the 2D ISM and submapped 3D grids of config/sim.ini) to `path`. */
std::string writeFastConfig(const std::string& path, bool maps = false);

/** Result of a command run through /bin/sh with `exec`, so the status is the tool's own. */
struct ToolRun
{
	int status{-1};  //!< raw wait status
	std::string output;  //!< stdout + stderr
	bool signaled() const;
	int termSignal() const;
	int exitCode() const;  //!< -1 unless exited normally
};

/** Runs `toolPath(tool) + " " + args` with stderr merged into stdout; `env` ("NAME=value ...")
 * is set for the tool only. */
ToolRun runTool(const std::string& tool, const std::string& args, const std::string& env = "");

/** Number of pose lines (non-comment, non-empty) in a TUM trajectory file. */
std::size_t countPoseLines(const std::string& path);

}  // namespace keygrid::test
