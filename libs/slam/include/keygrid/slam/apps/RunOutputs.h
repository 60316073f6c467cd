#pragma once
/** \file RunOutputs.h
 * The output files of one keygrid-slam run (doc/user-guide.md, "Outputs").
 *
 * RunOutputs writes each file on its own through core::AtomicOutput: a file that cannot be
 * written (full disk, permissions) is recorded with its reason, nothing partial keeps its
 * name, and the next file is still tried, so a failing run loses as little as it can.
 */
#include <keygrid/core/TumTrajectory.h>
#include <mrpt/poses/CPose3D.h>

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace keygrid::slam
{
class System;
struct SlamConfig;

class RunOutputs
{
   public:
	explicit RunOutputs(std::string dir) : m_dir(std::move(dir)) {}

	/** Runs `write`, which produces one or more files; an exception is recorded as an error
	 * (its text names the file) and does not propagate. Returns whether it succeeded. */
	bool write(const std::function<void()>& write);
	/** Writes `content` to `<dir>/<file>`. */
	bool text(const std::string& file, const std::string& content);

	const std::string& dir() const { return m_dir; }
	std::string path(const std::string& file) const { return m_dir + "/" + file; }
	/** Every failure, in the order the files were tried. */
	const std::vector<std::string>& errors() const { return m_errors; }

   private:
	std::string m_dir;
	std::vector<std::string> m_errors;
};

/** What the run's files are made of, besides the System. */
struct RunFilesInput
{
	const core::Trajectory& trajectory;  //!< the final one, as trajectory.txt lists it
	std::string trajectoryTitle;
	std::optional<mrpt::poses::CPose3D> T_world_floor;  //!< the maps' floor frame, if any
	bool hocEnabled{false};
};

/** Writes every file of a run except report.json: trajectories, frames.csv, keyframes,
 * keyframes.simplemap, scene.3Dscene, loop diagnostics, the pose graph, the metric maps. */
void writeRunFiles(System& sys, const SlamConfig& cfg, const RunFilesInput& in, RunOutputs& out);

}  // namespace keygrid::slam
