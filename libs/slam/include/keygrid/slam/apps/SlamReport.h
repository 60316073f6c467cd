#pragma once
/** \file SlamReport.h
 * report.json of a keygrid-slam run (doc/user-guide.md, "keygrid-slam outputs"): what was
 * read, tracked and mapped, timings, memory, loop closures, the session, errors.
 */
#include <keygrid/eval/TrajectoryErrors.h>
#include <keygrid/slam/SessionLoader.h>
#include <keygrid/slam/apps/SlamApp.h>

#include <optional>
#include <string>
#include <vector>

namespace keygrid::slam
{
class System;
class MemorySampler;

/** What report.json says besides what the System holds. */
struct SlamReportInput
{
	const SlamRunOptions& options;
	const SlamConfig& config;
	const SlamRunResult& result;  //!< frames, fps, error, skipped input entries, live counts
	std::string input;  //!< the input as described to the user
	bool live{false};
	const std::optional<LoadedSession>& loaded;  //!< --load-map
	double wallSeconds{0};
	const MemorySampler& memory;
	const std::optional<eval::TrajectoryErrors>& errors;  //!< --gt
	const std::vector<std::string>& outputErrors;
};

/** The text of report.json (pretty-printed, keys in a fixed order). */
std::string slamReportJson(const System& sys, const SlamReportInput& in);

}  // namespace keygrid::slam
