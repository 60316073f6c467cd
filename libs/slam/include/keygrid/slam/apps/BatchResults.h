#pragma once
/** \file BatchResults.h
 * keygrid-batch results: what one keygrid-slam run reported (its report.json), and the table
 * with one row per (dataset, config) — medians over repeats — as markdown and CSV.
 */
#include <optional>
#include <string>
#include <vector>

namespace keygrid::slam
{
/** The numbers of one run's report.json plus how the run ended. */
struct RunMetrics
{
	std::string dataset, config;
	int repeat{1};
	std::string runDir;
	std::string error;  //!< empty when the run succeeded
	std::optional<double> frames, tracked, fps, ateRmse, keyframes, landmarks, loopClosures;
	double seconds{0};  //!< wall clock of the process

	bool ok() const { return error.empty(); }
};

/** Reads frames, tracked, fps, ate_rmse_m, keyframes, landmarks, the number of entries of
 * loop_closures and error (null or a string) from a keygrid-slam report.json. Throws
 * std::runtime_error naming the file when it is missing or not valid JSON. */
RunMetrics readRunReport(const std::string& reportPath);

/** One row of the table: a (dataset, config) pair. */
struct ResultRow
{
	std::string dataset, config;
	int runs{0}, failed{0};
	/** Medians over the successful runs (over all runs when none succeeded). */
	std::optional<double> frames, tracked, fps, ateRmse, keyframes, landmarks, loopClosures;
	std::string error;  //!< "" or the first failed run's error ("2 of 3 runs failed: ...")
};

/** Median of the values present (mean of the two middle ones for an even count). */
std::optional<double> medianOf(const std::vector<std::optional<double>>& values);

/** Groups runs by (dataset, config), in the order the pairs first appear. */
std::vector<ResultRow> aggregateRuns(const std::vector<RunMetrics>& runs);

/** Markdown table: dataset | config | runs | frames | tracked | fps | ATE RMSE [cm] | keyframes
 * | landmarks | loop closures | error. */
std::string resultsMarkdown(const std::vector<ResultRow>& rows);

/** CSV with header dataset,config,runs,failed,frames,tracked,fps,ate_rmse_m,keyframes,landmarks,
 * loop_closures,error (ATE in metres, full precision; empty cells for missing values). */
std::string resultsCsv(const std::vector<ResultRow>& rows);

/** CSV of every single run: dataset,config,repeat,seconds,<the metrics>,error,run_dir. */
std::string runsCsv(const std::vector<RunMetrics>& runs);

}  // namespace keygrid::slam
