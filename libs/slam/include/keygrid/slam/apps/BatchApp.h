#pragma once
/** \file BatchApp.h
 * keygrid-batch: runs an experiment (EXPERIMENT.ini: datasets x configurations, see
 * BatchExperiment.h and doc/user-guide.md) as parallel keygrid-slam processes, evaluates each
 * run against ground truth and writes OUT/results.md + OUT/results.csv (one row per
 * (dataset, config), medians over repeats) and OUT/runs.csv (every run).
 */
#include <keygrid/slam/apps/BatchExperiment.h>
#include <keygrid/slam/apps/BatchResults.h>

#include <string>
#include <vector>

namespace keygrid::slam
{
struct BatchRunOptions
{
	/** Folder holding keygrid-slam and keygrid-sim (Default: this executable's folder) */
	std::string binDir;
	/** Print the commands instead of running them */
	bool dryRun{false};
	/** The command line, recorded in results.md */
	std::string commandLine;
};

/** Generates the synthetic datasets, runs the matrix, writes the tables; returns every run. A
 * failed run (or dataset generation) becomes a run with its error, never an exception; bad
 * experiment specs (unknown override keys, invalid configurations) throw before anything runs. */
std::vector<RunMetrics> runBatch(const ExperimentSpec& spec, const BatchRunOptions& opts);

class BatchApp
{
   public:
	int run(int argc, const char* const* argv);
};

}  // namespace keygrid::slam
