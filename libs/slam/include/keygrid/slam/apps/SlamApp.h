#pragma once
/** \file SlamApp.h
 * keygrid-slam: run the SLAM pipeline on a rawlog or TUM folder and write the trajectory,
 * keyframes and report.
 */
#include <keygrid/slam/SlamConfig.h>

#include <optional>
#include <string>
#include <vector>

namespace keygrid::slam
{
struct SlamRunOptions
{
	std::string configPath, input, output, groundTruth;
	std::optional<RunMode> modeOverride;
	std::optional<std::string> cameraOverride;
	/** `section.key=value; ...` applied to an in-memory copy of the configuration file
	 * (keygrid-slam --set); every key must exist in the file or in keygrid-slam's options. */
	std::string set;
	std::size_t maxFrames{0};  //!< 0 = all
	/** Input frames skipped before the first processed one (0 = none) */
	std::size_t firstFrame{0};
	/** --map: a new session file the run is recorded into (empty: none) */
	std::string mapFile;
	/** --load-map: a stored session loaded before the first frame (empty: none) */
	std::string loadMap;
	/** --localize (with loadMap): track in the loaded map without changing it */
	bool localize{false};
	bool quiet{false};
	/** Grab from the OpenNI2 camera of the config's [live] section instead of `input` */
	bool live{false};
	/** With live: show the image with tracked keypoints in a window */
	bool preview{false};
};

/** What a run produced (also written to report.json). */
struct SlamRunResult
{
	std::size_t frames{0}, tracked{0};
	double fps{0};
	std::optional<double> ateRmse;
	/** The first problem: the input or the processing failed part-way (the outputs are still
	 * written), or else the first output file that could not be written. Empty: success. */
	std::string error;
	/** Output files that could not be written, each error naming its file */
	std::vector<std::string> outputErrors;
	/** The frame loop was stopped by interruptRequested() (Ctrl-C / SIGTERM) */
	bool interrupted{false};
	std::size_t liveGrabbed{0}, liveDropped{0};  //!< live runs: camera frames, and those skipped
	/** Localization mode: frames localized in the loaded map */
	std::size_t localized{0};
	/** Input entries skipped (not RGB-D, unreadable, or a timestamp not after the previous
	 * frame's), and why the last one was */
	std::size_t skipped{0};
	std::string lastSkip;
};

/** The text of configuration file `path` with the `--set` overrides `set` applied (their keys
 * checked first: MRPT would ignore a misspelt one); every reader of one run sees this text.
 * Throws std::invalid_argument naming the file or the bad override. */
std::string effectiveConfigText(const std::string& path, const std::string& set);

/** Runs one sequence end to end; throws on bad configuration or unopenable input. */
SlamRunResult runSlam(const SlamRunOptions& opts);

class SlamApp
{
   public:
	int run(int argc, const char* const* argv);
};

}  // namespace keygrid::slam
