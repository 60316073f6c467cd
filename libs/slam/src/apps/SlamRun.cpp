/** \file SlamRun.cpp
 * runSlam(): one keygrid-slam run end to end. Configuration, input, the frame loop (live or
 * recorded), the final step, the final trajectory, the output files (RunOutputs.h) and
 * report.json (SlamReport.h), each in a function of its own.
 */
#include <keygrid/core/ConfigReading.h>
#include <keygrid/core/FrameSource.h>
#include <keygrid/core/PrefetchingFrameSource.h>
#include <keygrid/core/ProgressBar.h>
#include <keygrid/eval/TrajectoryErrors.h>
#include <keygrid/slam/Interrupt.h>
#include <keygrid/slam/LiveRun.h>
#include <keygrid/slam/ProcessMemory.h>
#include <keygrid/slam/RecordedRun.h>
#include <keygrid/slam/System.h>
#include <keygrid/store/SessionStore.h>
#include <keygrid/slam/apps/BatchExperiment.h>
#include <keygrid/slam/apps/RunOutputs.h>
#include <keygrid/slam/apps/SlamReport.h>
#include <keygrid/slam/apps/SlamApp.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/system/filesystem.h>
#include <opencv2/core/utility.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>

namespace keygrid::slam
{
namespace
{
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/** OpenCV's own worker threads off for the lifetime of a run, restored afterwards. The run
 * already keeps the cores busy with its pipeline (decoding, extraction, tracking and mapping
 * on their own threads); OpenCV parallelising the extraction on top of that preempts tracking
 * and lowers the frame rate (doc/frontend.md "Modes"). */
class OpenCvThreadsOff
{
   public:
	OpenCvThreadsOff() : m_previous(cv::getNumThreads()) { cv::setNumThreads(1); }
	~OpenCvThreadsOff() { cv::setNumThreads(m_previous); }
	OpenCvThreadsOff(const OpenCvThreadsOff&) = delete;
	OpenCvThreadsOff& operator=(const OpenCvThreadsOff&) = delete;

   private:
	int m_previous;
};

/** The run's configuration: the file (with --set) and the --mode / --camera overrides. */
SlamConfig runConfig(const mrpt::config::CConfigFileMemory& ini, const SlamRunOptions& o)
{
	SlamConfig cfg = SlamConfig::FromConfig(ini, o.configPath);
	if (o.modeOverride) cfg.mode = *o.modeOverride;
	if (o.cameraOverride) cfg.camera = *o.cameraOverride;
	return cfg;
}

/** Creates the output folder with its parents (--output runs/today/seq1); a file in the way
 * is named. */
void createOutputFolder(const std::string& dir)
{
	std::error_code ec;
	std::filesystem::create_directories(dir, ec);
	if (ec || !mrpt::system::directoryExists(dir))
		throw std::runtime_error("cannot create output folder '" + dir + "'" + (ec ? ": " + ec.message() : std::string()));
}

/** The --gt trajectory (none without --gt), read before the input is opened, not after the run. */
std::optional<core::Trajectory> readGroundTruth(const std::string& path)
{
	if (path.empty()) return std::nullopt;
	auto gt = core::readTumTrajectory(path);
	if (gt.empty()) throw std::invalid_argument("ground truth '" + path + "' holds no poses");
	return gt;
}

/** The frames of a run: a recorded input decoded ahead on its own thread (frames keep their
 * order), or the live camera's newest frame only (LiveRun.h). */
struct RunInput
{
	std::unique_ptr<core::PrefetchingFrameSource> recorded;
	std::unique_ptr<LiveFrameSource> live;

	core::FrameSource& source() { return live ? static_cast<core::FrameSource&>(*live) : *recorded; }
};

RunInput openRunInput(const SlamRunOptions& o, const mrpt::config::CConfigFileMemory& ini, const SlamConfig& cfg)
{
	core::FrameSourceOptions so;
	if (!cfg.camera.empty() && cfg.camera != "auto") so.camera = core::RgbdCamera::FromPresetOrFile(cfg.camera);
	// Monocular: the images alone, whatever else the input holds.
	if (cfg.sensor == Sensor::Monocular) so.depth = core::DepthUse::Ignore;
	RunInput in;
	if (o.live && cfg.sensor == Sensor::Monocular)
		throw std::invalid_argument("[slam] sensor = monocular: the live camera (OpenNI2) is RGB-D only; record a plain camera with rawlog-grabber (config/rawlog-grabber/usb_camera.ini) and run on the rawlog");
	if (o.live)
		in.live = openLiveCamera(ini, o.configPath, cfg);
	else
		in.recorded = std::make_unique<core::PrefetchingFrameSource>(core::openFrameSource(o.input, so), 4);
	return in;
}

/** Attaches the metric maps, the loaded session (--load-map) and the session recorder (--map,
 * or the loaded file itself in extend mode) to `sys`; returns what was loaded. */
std::optional<LoadedSession> attachRunComponents(
	System& sys, const mrpt::config::CConfigFileMemory& ini, const SlamConfig& cfg, const SlamRunOptions& o)
{
	if (!o.localize)
	{
		// Localization adds no keyframes: no map is fed. Extend mode re-integrates the stored
		// keyframes into them when the session is loaded.
		auto maps = std::make_unique<MetricMaps>(ini, cfg.maps, cfg.floor);
		if (!maps->empty()) sys.attachMaps(std::move(maps));
	}
	std::optional<LoadedSession> loaded;
	if (!o.loadMap.empty())
	{
		auto session = store::SessionStore::Open(
			o.loadMap, o.localize ? store::SessionStore::Mode::ReadOnly : store::SessionStore::Mode::ReadWrite, cfg.store.sqlite);
		loaded = sys.loadSession(session, o.localize);
		if (!o.quiet)
			std::cerr << "keygrid-slam: loaded " << o.loadMap << ": " << loaded->keyframes << " keyframes, " << loaded->landmarks
					  << " landmarks (" << loaded->seconds << " s)" << (o.localize ? ", localization only" : ", extending it") << "\n";
		// Extend mode: the run's changes go into the same file.
		if (!o.localize) sys.attachRecorder(std::make_unique<SessionRecorder>(std::move(session), sys.map(), cfg.store));
	}
	if (!o.mapFile.empty()) sys.attachRecorder(std::make_unique<SessionRecorder>(o.mapFile, cfg.store));
	return loaded;
}

/** Runs the frames of `in` through `sys` (live or recorded loop) with a progress bar and the
 * memory samples of report.json. An error of the input or of the processing is kept in
 * res.error: the frames before it still count and the outputs are still written. Fills the
 * live counters of `res`; returns the frames dropped for their timestamps. */
TimestampSkips processFrames(
	System& sys, RunInput& in, const SlamRunOptions& o, const SlamConfig& cfg, Clock::time_point tStart, MemorySampler& memory,
	SlamRunResult& res)
{
	core::FrameSource& input = in.source();
	const std::size_t total = o.maxFrames ? std::min(o.maxFrames, input.sizeHint().value_or(o.maxFrames)) : input.sizeHint().value_or(0);
	core::ProgressBar bar("keygrid-slam", total, !o.quiet);
	if (!o.quiet) std::cerr << "keygrid-slam: " << input.describe() << ", " << (in.live ? "live" : toString(cfg.mode)) << " mode\n";
	auto report = [&](const sfm::TrackedFrame& tf) {
		const double el = since(tStart);
		char extra[128];
		const auto st = sys.stats();
		memory.onFrame(sys.numKeyFrames(), st.frames);
		std::snprintf(extra, sizeof(extra), "%.1f fps, kf %zu, lost %zu%s", st.frames / std::max(el, 1e-9),
					  sys.numKeyFrames(), st.lost, tf.tracked ? "" : " (LOST)");
		bar.update(st.frames, extra);
	};
	std::optional<RecordedFrameLoop> recordedLoop;
	if (in.recorded) recordedLoop.emplace(sys, *in.recorded, RecordedLoopOptions{o.firstFrame, o.maxFrames, cfg.playbackRate});
	try
	{
		if (in.live)
		{
			LiveLoopOptions lo;
			lo.preview = o.preview;
			lo.maxFrames = o.maxFrames;
			const auto lr = runLiveLoop(sys, *in.live, lo, report);
			res.liveGrabbed = lr.grabbed;
			res.liveDropped = lr.dropped;
		}
		else
			recordedLoop->run(report);
	}
	catch (const std::exception& e)
	{
		res.error = e.what();
	}
	bar.finish();
	return recordedLoop ? recordedLoop->timestampSkips() : TimestampSkips{};
}

/** Input entries skipped (by the source, or for their timestamps) into `res`, with a warning;
 * a run that processed no frame at all (and was not interrupted) fails naming the last skip. */
void noteSkippedInput(const System& sys, const RunInput& in, const TimestampSkips& timestampSkips, SlamRunResult& res)
{
	const std::size_t skipped = (in.live ? in.live->innerSkipped() : in.recorded->innerSkipped()) + timestampSkips.count;
	std::string lastSkip = timestampSkips.last;
	if (lastSkip.empty() && in.recorded) lastSkip = in.recorded->innerLastSkipReason();
	res.skipped = skipped;
	res.lastSkip = lastSkip;
	if (res.error.empty() && sys.stats().frames == 0 && !interruptRequested())
		res.error = std::string(sys.config().sensor == Sensor::Monocular ? "no image frame" : "no RGB-D frame") + " in the input" + (skipped ? " (" + std::to_string(skipped) + " entries skipped, the last: " + lastSkip + ")" : std::string());
	if (skipped)
		std::cerr << "keygrid-slam: warning: skipped " << skipped << " input entries"
				  << (lastSkip.empty() ? std::string() : " (last: " + lastSkip + ")") << "\n";
}

/** The final step (global bundle adjustment, map re-anchoring, frame refinement) as one stage,
 * after noting an interruption; an error of the mapping side becomes the run's error. */
void finishRun(System& sys, const SlamRunOptions& o, SlamRunResult& res)
{
	res.interrupted = interruptRequested();
	if (res.interrupted && !o.quiet)
		std::cerr << "keygrid-slam: interrupted after " << sys.stats().frames << " frames, writing the outputs\n";
	const auto tFinish = Clock::now();
	sys.finish();
	sys.timings().add("finish", since(tFinish));
	if (res.error.empty()) res.error = sys.backgroundError();
}

/** trajectory.txt's poses and title. */
struct FinalTrajectory
{
	core::Trajectory poses;
	std::string title;
};

/** Every frame's final pose; with a loaded map only the frames that have a pose in it:
 * localization lists the localized frames (counted in res.localized), extend mode the frames
 * from the first tracked one on; monocular mode the frames from the map's first keyframe on. */
FinalTrajectory finalTrajectory(const System& sys, bool mapLoaded, const SlamRunOptions& o, SlamRunResult& res)
{
	FinalTrajectory t{sys.trajectory(), "keygrid-slam trajectory, every frame"};
	if (sys.localizeOnly())
	{
		core::Trajectory localized;
		for (std::size_t i = 0; i < t.poses.size() && i < sys.frames().size(); i++)
			if (sys.frames()[i].tracked) localized.push_back(t.poses[i]);
		t.poses = std::move(localized);
		res.localized = t.poses.size();
		t.title = "keygrid-slam trajectory in the loaded map's frame, every localized frame";
	}
	else if (mapLoaded)
	{
		// The frames before the camera found its place (in the stored map or in a new one)
		// have no pose.
		std::size_t first = 0;
		while (first < sys.frames().size() && !sys.frames()[first].tracked) first++;
		t.poses.erase(t.poses.begin(), t.poses.begin() + static_cast<std::ptrdiff_t>(std::min(first, t.poses.size())));
		t.title = "keygrid-slam trajectory in the loaded map's frame, every frame from the first tracked one";
		const auto ex = sys.extendState();
		if (ex.waitingForMerge > 0 && !o.quiet)
			std::cerr << "keygrid-slam: warning: the new map never met the stored one; its " << ex.waitingForMerge
					  << " keyframes are in a frame of their own, not in the metric maps nor in " << o.loadMap << "\n";
	}
	else if (sys.config().sensor == Sensor::Monocular)
	{
		// The frames before the map started have no pose (two-view initialization), except
		// the reference frame that became its first keyframe.
		const auto& frames = sys.frames();
		std::size_t start = 0;
		while (start < frames.size() && frames[start].method != sfm::TrackingMethod::Init) start++;
		core::Trajectory kept;
		for (std::size_t i = 0; i < t.poses.size() && i < frames.size(); i++)
			if (i >= start || frames[i].hasReference) kept.push_back(t.poses[i]);
		t.poses = std::move(kept);
		t.title = "keygrid-slam trajectory, every frame from the map start on (monocular: arbitrary scale)";
	}
	return t;
}

/** Every output file but report.json (RunOutputs.h); a file not written becomes the run's
 * error when it has none. */
void writeOutputFiles(System& sys, const SlamConfig& cfg, const FinalTrajectory& traj, RunOutputs& outputs, SlamRunResult& res)
{
	// The run's floor frame (any map configured): every map output is written in it.
	std::optional<mrpt::poses::CPose3D> T_world_floor;
	if (sys.metricMaps()) T_world_floor = sys.metricMaps()->T_world_floor();
	writeRunFiles(sys, cfg, {traj.poses, traj.title, T_world_floor, cfg.tracker.hoc.enabled}, outputs);
	if (res.error.empty() && !outputs.errors().empty()) res.error = outputs.errors().front();
}

/** ATE and RPE of the final trajectory against --gt (at least three poses), after a Sim(3)
 * alignment for a map without metric units; a failed evaluation becomes the run's error when it
 * has none. */
std::optional<eval::TrajectoryErrors> evaluateAgainstGroundTruth(
	const std::optional<core::Trajectory>& gt, const core::Trajectory& traj, bool metricUnits, SlamRunResult& res)
{
	if (!gt || traj.size() < 3) return std::nullopt;
	try
	{
		// A monocular trajectory without metric scale has the map's arbitrary unit: aligned
		// with a Sim(3).
		eval::TrajectoryErrorOptions eo;
		eo.withScale = !metricUnits;
		auto errs = eval::evaluateTrajectory(*gt, traj, eo);
		res.ateRmse = errs.ate.rmse;
		return errs;
	}
	catch (const std::exception& e)
	{
		if (res.error.empty()) res.error = std::string("evaluation: ") + e.what();
	}
	return std::nullopt;
}
}  // namespace

std::string effectiveConfigText(const std::string& path, const std::string& set)
{
	if (!mrpt::system::fileExists(path)) throw std::invalid_argument("config file '" + path + "' does not exist");
	if (std::filesystem::is_directory(path)) throw std::invalid_argument("config file '" + path + "' is a folder, not a file");
	std::string text = mrpt::io::file_get_contents(path);
	core::checkIniText(text, path);
	if (set.empty()) return text;
	const auto overrides = parseOverrides(set, "--set");
	checkOverrideKeys(text, overrides, "--set");
	return applyOverrides(text, overrides);
}

SlamRunResult runSlam(const SlamRunOptions& o)
{
	const mrpt::config::CConfigFileMemory ini(effectiveConfigText(o.configPath, o.set));
	const SlamConfig cfg = runConfig(ini, o);
	createOutputFolder(o.output);
	const std::optional<core::Trajectory> gt = readGroundTruth(o.groundTruth);
	const OpenCvThreadsOff openCvThreadsOff;
	RunInput input = openRunInput(o, ini, cfg);
	System sys(cfg);
	const std::optional<LoadedSession> loaded = attachRunComponents(sys, ini, cfg, o);

	SlamRunResult res;
	const auto tStart = Clock::now();
	MemorySampler memory(25);  // report.json "rss_mb_by_keyframes"
	const TimestampSkips timestampSkips = processFrames(sys, input, o, cfg, tStart, memory, res);
	noteSkippedInput(sys, input, timestampSkips, res);
	finishRun(sys, o, res);
	const double wall = since(tStart);

	const FinalTrajectory traj = finalTrajectory(sys, loaded.has_value(), o, res);
	RunOutputs outputs(o.output);
	writeOutputFiles(sys, cfg, traj, outputs, res);
	res.frames = sys.stats().frames;
	res.tracked = sys.stats().tracked;
	res.fps = res.frames / std::max(wall, 1e-9);
	const auto errs = evaluateAgainstGroundTruth(gt, traj.poses, sys.metricUnits(), res);

	const SlamReportInput reportInput{
		o, cfg, res, input.live ? input.live->describe() : o.input, static_cast<bool>(input.live), loaded, wall, memory, errs, outputs.errors()};
	outputs.text("report.json", slamReportJson(sys, reportInput));
	res.outputErrors = outputs.errors();
	if (res.error.empty() && !res.outputErrors.empty()) res.error = res.outputErrors.front();
	return res;
}

}  // namespace keygrid::slam
