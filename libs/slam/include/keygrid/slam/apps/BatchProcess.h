#pragma once
/** \file BatchProcess.h
 * Child processes for keygrid-batch: run a list of commands (argv vectors, no shell) with at
 * most N at a time, each with stdout + stderr going to its own log file, an optional time
 * limit, and a callback as each one ends.
 */
#include <functional>
#include <string>
#include <vector>

namespace keygrid::slam
{
struct ProcessJob
{
	std::vector<std::string> argv;  //!< argv[0] is the executable's path
	std::string logPath;            //!< stdout and stderr (truncated); its folder must exist
};

struct ProcessOutcome
{
	int exitCode{-1};         //!< exit status when the process exited normally, else -1
	int signal{0};            //!< the signal that ended it, 0 if it exited
	bool timedOut{false};     //!< stopped because of the time limit
	std::string launchError;  //!< non-empty when the process could not be started
	double seconds{0};        //!< wall-clock time

	bool succeeded() const { return launchError.empty() && !timedOut && signal == 0 && exitCode == 0; }
	/** "exit code 3", "killed by signal 9", "timed out after 10 s", "cannot start ...". */
	std::string describe() const;
};

/** Runs every job, at most `parallel` (>= 1) at once, in list order. A job running longer than
 * `timeoutSeconds` (> 0) gets SIGTERM, then SIGKILL 5 s later. onDone(index, outcome) runs on
 * the calling thread as each job ends. Returns the outcomes in job order. */
std::vector<ProcessOutcome> runProcesses(
	const std::vector<ProcessJob>& jobs, int parallel, double timeoutSeconds,
	const std::function<void(std::size_t, const ProcessOutcome&)>& onDone = {});

/** A command line as text, for logs and --dry-run (arguments with blanks are quoted). */
std::string commandText(const std::vector<std::string>& argv);

}  // namespace keygrid::slam
