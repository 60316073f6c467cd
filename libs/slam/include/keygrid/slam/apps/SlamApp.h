#pragma once
/** \file SlamApp.h
 * keygrid-slam: run the SLAM pipeline on a rawlog or TUM folder and write the trajectory,
 * keyframes and report.
 */
#include <keygrid/slam/SlamConfig.h>

#include <optional>
#include <string>

namespace keygrid::slam
{
struct SlamRunOptions
{
	std::string configPath, input, output, groundTruth;
	std::optional<std::string> modeOverride, cameraOverride;
	std::size_t maxFrames{0};  //!< 0 = all
	bool quiet{false};
};

/** What a run produced (also written to report.json). */
struct SlamRunResult
{
	std::size_t frames{0}, tracked{0};
	double fps{0};
	std::optional<double> ateRmse;
	std::string error;  //!< non-empty when the input failed part-way (outputs still written)
};

/** Runs one sequence end to end; throws on bad configuration or unopenable input. */
SlamRunResult runSlam(const SlamRunOptions& opts);

class SlamApp
{
   public:
	int run(int argc, const char* const* argv);
};

}  // namespace keygrid::slam
