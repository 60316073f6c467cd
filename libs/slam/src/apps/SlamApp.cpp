#include <keygrid/core/ConfigReading.h>
#include <keygrid/core/BoundedQueue.h>
#include <keygrid/core/CommandLine.h>
#include <keygrid/core/FrameSource.h>
#include <keygrid/core/PrefetchingFrameSource.h>
#include <keygrid/core/ProgressBar.h>
#include <keygrid/eval/TrajectoryErrors.h>
#include <keygrid/core/AtomicOutput.h>
#include <keygrid/slam/Interrupt.h>
#include <keygrid/slam/LivePreview.h>
#include <keygrid/slam/LiveRun.h>
#include <keygrid/slam/ProcessMemory.h>
#include <keygrid/slam/IniReference.h>
#include <keygrid/slam/System.h>
#include <keygrid/store/SessionStore.h>
#include <keygrid/slam/apps/AppRunner.h>
#include <keygrid/slam/apps/BatchExperiment.h>
#include <keygrid/slam/apps/RunOutputs.h>
#include <keygrid/slam/apps/SlamReport.h>
#include <keygrid/slam/apps/SlamApp.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/system/filesystem.h>
#include <opencv2/core/utility.hpp>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <thread>

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

struct Extracted
{
	core::Frame frame;
	sfm::FrameFeatures features;
	double loadSeconds{0}, extractSeconds{0};
};
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
	SlamConfig cfg = SlamConfig::FromConfig(ini, o.configPath);
	if (o.modeOverride) cfg.mode = *o.modeOverride;
	if (o.cameraOverride) cfg.camera = *o.cameraOverride;
	{
		// Parents too (--output runs/today/seq1); a file in the way is named.
		std::error_code ec;
		std::filesystem::create_directories(o.output, ec);
		if (ec || !mrpt::system::directoryExists(o.output))
			throw std::runtime_error("cannot create output folder '" + o.output + "'" + (ec ? ": " + ec.message() : std::string()));
	}
	std::optional<core::Trajectory> gt;
	if (!o.groundTruth.empty())
	{
		// Checked before the input is opened, not after the run.
		gt = core::readTumTrajectory(o.groundTruth);
		if (gt->empty()) throw std::invalid_argument("ground truth '" + o.groundTruth + "' holds no poses");
	}
	const OpenCvThreadsOff openCvThreadsOff;
	core::FrameSourceOptions so;
	if (!cfg.camera.empty() && cfg.camera != "auto") so.camera = core::RgbdCamera::FromPresetOrFile(cfg.camera);
	// Files: decoding runs ahead on its own thread in both modes; frames keep their order.
	// Live: the camera's newest frame only (LiveRun.h).
	std::unique_ptr<core::PrefetchingFrameSource> source;
	std::unique_ptr<LiveFrameSource> live;
	if (o.live)
		live = openLiveCamera(ini, o.configPath, cfg);
	else
		source = std::make_unique<core::PrefetchingFrameSource>(core::openFrameSource(o.input, so), 4);
	core::FrameSource& input = live ? static_cast<core::FrameSource&>(*live) : *source;

	System sys(cfg);
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
	SlamRunResult res;
	const std::size_t total = o.maxFrames ? std::min(o.maxFrames, input.sizeHint().value_or(o.maxFrames)) : input.sizeHint().value_or(0);
	core::ProgressBar bar("keygrid-slam", total, !o.quiet);
	if (!o.quiet) std::cerr << "keygrid-slam: " << input.describe() << ", " << (live ? "live" : toString(cfg.mode)) << " mode\n";
	const auto tStart = Clock::now();
	MemorySampler memory(25);  // report.json "rss_mb_by_keyframes"
	auto report = [&](const sfm::TrackedFrame& tf) {
		const double el = since(tStart);
		char extra[128];
		const auto st = sys.stats();
		memory.onFrame(sys.numKeyFrames(), st.frames);
		std::snprintf(extra, sizeof(extra), "%.1f fps, kf %zu, lost %zu%s", st.frames / std::max(el, 1e-9),
					  sys.numKeyFrames(), st.lost, tf.tracked ? "" : " (LOST)");
		bar.update(st.frames, extra);
	};
	auto limitReached = [&](std::size_t n) { return o.maxFrames && n >= o.maxFrames; };
	struct
	{
		std::size_t count{0};
		std::string last;
		void note(const std::string& why)
		{
			++count;
			last = why;
		}
	} timeSkips;  // frames dropped for their timestamps (the producer thread's, read after it joined)

	try
	{
		if (live)
		{
			LiveLoopOptions lo;
			lo.preview = o.preview;
			lo.maxFrames = o.maxFrames;
			const auto lr = runLiveLoop(sys, *live, lo, report);
			res.liveGrabbed = lr.grabbed;
			res.liveDropped = lr.dropped;
		}
		else
		{
			// Decoding (prefetch thread) -> feature extraction (producer thread) -> tracking, then
			// (sequential mode) local mapping and loop closing in order on this thread, joined by
			// typed bounded queues. Decoding and extraction are functions of the frame alone, so
			// running them ahead keeps sequential mode deterministic.
			core::BoundedQueue<Extracted> queue(4);
			std::string producerError;
			std::thread producer([&] {
				try
				{
					core::Frame skippedFrame;
					for (std::size_t n = 0; n < o.firstFrame && !interruptRequested(); n++)
						if (!source->next(skippedFrame)) break;
					std::optional<double> lastStamp;
					for (std::size_t n = 0; !limitReached(n) && !interruptRequested();)
					{
						Extracted e;
						if (!source->next(e.frame)) break;
						// Time must go forward: a frame without a timestamp, or not after the
						// previous one, would give the trajectory a repeated or backward stamp.
						if (!(e.frame.timestamp > 0) || (lastStamp && !(e.frame.timestamp > *lastStamp)))
						{
							char why[160];
							std::snprintf(why, sizeof(why), "frame %zu: timestamp %.6f %s", e.frame.index, e.frame.timestamp,
										  e.frame.timestamp > 0 ? "is not after the previous frame's" : "is missing");
							timeSkips.note(why);
							continue;
						}
						lastStamp = e.frame.timestamp;
						n++;
						e.loadSeconds = source->lastLoadSeconds();
						const auto t0 = Clock::now();
						e.features = sys.extract(e.frame);
						e.extractSeconds = since(t0);
						if (!queue.push(std::move(e))) break;
					}
				}
				catch (const std::exception& ex)
				{
					producerError = ex.what();
				}
				queue.close();
			});
			try
			{
				for (;;)
				{
					const auto tWait = Clock::now();
					auto e = queue.pop();
					if (!e) break;
					sys.timings().add("input_wait", since(tWait));
					sys.timings().add("load", e->loadSeconds);
					sys.timings().add("extract", e->extractSeconds);
					const auto t0 = Clock::now();
					report(sys.processExtracted(e->frame, std::move(e->features)));
					sys.timings().add("track_and_map", since(t0));
				}
			}
			catch (...)
			{
				queue.close();  // a joinable std::thread must not be destroyed
				producer.join();
				throw;
			}
			producer.join();
			if (!producerError.empty()) throw std::runtime_error(producerError);
		}
	}
	catch (const std::exception& e)
	{
		// Keep what was processed: outputs are still written below.
		res.error = e.what();
	}
	bar.finish();
	const std::size_t skipped = (live ? live->innerSkipped() : source->innerSkipped()) + timeSkips.count;
	const std::string lastSkip = !timeSkips.last.empty() ? timeSkips.last : live ? std::string() : source->innerLastSkipReason();
	res.skipped = skipped;
	res.lastSkip = lastSkip;
	if (res.error.empty() && sys.stats().frames == 0 && !interruptRequested())
		res.error = "no RGB-D frame in the input" + (skipped ? " (" + std::to_string(skipped) + " entries skipped, the last: " + lastSkip + ")" : std::string());
	if (skipped)
		std::cerr << "keygrid-slam: warning: skipped " << skipped << " input entries"
				  << (lastSkip.empty() ? std::string() : " (last: " + lastSkip + ")") << "\n";
	res.interrupted = interruptRequested();
	if (res.interrupted && !o.quiet)
		std::cerr << "keygrid-slam: interrupted after " << sys.stats().frames << " frames, writing the outputs\n";
	{
		// The final step (global bundle adjustment, map re-anchoring, frame refinement) as one.
		const auto tFinish = Clock::now();
		sys.finish();
		sys.timings().add("finish", since(tFinish));
	}
	if (res.error.empty()) res.error = sys.backgroundError();
	const double wall = since(tStart);

	auto traj = sys.trajectory();
	std::string trajectoryTitle = "keygrid-slam trajectory, every frame";
	if (sys.localizeOnly())
	{
		// A frame not localized has no pose in the map: only the localized ones are listed.
		core::Trajectory localized;
		for (std::size_t i = 0; i < traj.size() && i < sys.frames().size(); i++)
			if (sys.frames()[i].tracked) localized.push_back(traj[i]);
		traj = std::move(localized);
		res.localized = traj.size();
		trajectoryTitle = "keygrid-slam trajectory in the loaded map's frame, every localized frame";
	}
	else if (loaded)
	{
		// Extend mode: the frames before the camera found its place (in the stored map or in a
		// new one) have no pose.
		std::size_t first = 0;
		while (first < sys.frames().size() && !sys.frames()[first].tracked) first++;
		traj.erase(traj.begin(), traj.begin() + static_cast<std::ptrdiff_t>(std::min(first, traj.size())));
		trajectoryTitle = "keygrid-slam trajectory in the loaded map's frame, every frame from the first tracked one";
		const auto ex = sys.extendState();
		if (ex.waitingForMerge > 0 && !o.quiet)
			std::cerr << "keygrid-slam: warning: the new map never met the stored one; its " << ex.waitingForMerge
					  << " keyframes are in a frame of their own, not in the metric maps nor in " << o.loadMap << "\n";
	}
	RunOutputs outputs(o.output);
	// The run's floor frame (any map configured): every map output is written in it.
	std::optional<mrpt::poses::CPose3D> T_world_floor;
	if (sys.metricMaps()) T_world_floor = sys.metricMaps()->T_world_floor();
	writeRunFiles(sys, cfg, {traj, trajectoryTitle, T_world_floor, cfg.tracker.hoc.enabled}, outputs);
	if (res.error.empty() && !outputs.errors().empty()) res.error = outputs.errors().front();
	res.frames = sys.stats().frames;
	res.tracked = sys.stats().tracked;
	res.fps = res.frames / std::max(wall, 1e-9);
	std::optional<eval::TrajectoryErrors> errs;
	if (gt && traj.size() >= 3)
	{
		try
		{
			errs = eval::evaluateTrajectory(*gt, traj);
			res.ateRmse = errs->ate.rmse;
		}
		catch (const std::exception& e)
		{
			if (res.error.empty()) res.error = std::string("evaluation: ") + e.what();
		}
	}

	const SlamReportInput reportInput{o, cfg, res, live ? live->describe() : o.input, static_cast<bool>(live), loaded, wall, memory, errs, outputs.errors()};
	outputs.text("report.json", slamReportJson(sys, reportInput));
	res.outputErrors = outputs.errors();
	if (res.error.empty() && !res.outputErrors.empty()) res.error = res.outputErrors.front();
	return res;
}

int SlamApp::run(int argc, const char* const* argv)
{
	return runApp("keygrid-slam", [&] {
		core::CommandLine cl(
			"keygrid-slam",
			"RGB-D SLAM on a recorded sequence: keyframe-based ORB/SIFT tracking with local bundle\n"
			"adjustment. Writes DIR/trajectory.txt (TUM, every frame), DIR/keyframes.txt and\n"
			"DIR/report.json (frames, tracked, fps, per-stage timings, map sizes, and ATE with --gt).");
		cl.option("config", "CFG.ini", "configuration (see config/*.ini) (required)")
			.option("input", "X.rawlog|TUM_DIR", "MRPT rawlog or TUM RGB-D folder (required unless --live)")
			.option("output", "DIR", "output folder, created if missing (required)")
			.option("gt", "GT.txt", "ground-truth trajectory (TUM) to report ATE against")
			.option("mode", "sequential|threaded", "override [slam] mode")
			.option("camera", "PRESET|FILE.ini", "override [slam] camera (TUM folders)")
			.option("max-frames", "N", "stop after N frames", false, "0 (all)")
			.option("first-frame", "N", "skip the first N input frames", false, "0")
			.option("map", "FILE", "record the run into a new session file (keyframes, landmarks, images, map snapshots; doc/session-store.md)")
			.option("load-map", "FILE", "start from a stored session: extend it (the run is recorded into FILE), or with --localize track in it")
			.flag("localize", "with --load-map: track in the stored map without adding to it; FILE is not changed")
			.option(
				"set", "SECTION.KEY=V[;...]",
				"override configuration keys without editing the file, e.g. 'hoc.enabled=true; "
				"features.num_features=1200' (unknown keys are errors)")
			.flag("quiet", "no progress output")
			.flag("live", "grab from the OpenNI2 camera (Kinect/Xtion) of the config's [live] section in real time; Ctrl-C ends the run")
			.flag("preview", "with --live: show the image and tracked keypoints (default when $DISPLAY is set)")
			.flag("no-preview", "with --live: no preview window")
			.flag("dump-config", "print the full effective configuration (defaults, or --config merged over them) and exit")
			.flag("ini-reference", "print the INI reference (markdown: every section and map plugin, key | default | description) and exit");
		if (!cl.parse(argc, argv)) return 0;
		if (cl.flagSet("ini-reference"))
		{
			std::cout << iniReferenceMarkdown();
			return 0;
		}
		if (cl.flagSet("dump-config"))
		{
			if (cl.has("set") && !cl.has("config")) throw core::CommandLineError("--set needs --config");
			const SlamConfig c = cl.has("config") ? SlamConfig::FromConfig(
				mrpt::config::CConfigFileMemory(effectiveConfigText(cl.get("config"), cl.has("set") ? cl.get("set") : "")),
				cl.get("config")) : SlamConfig();
			mrpt::config::CConfigFileMemory mem;
			c.saveToConfigFile(mem);
			std::cout << "# keygrid-slam effective configuration\n" << mem.getContent();
			return 0;
		}
		const bool live = cl.flagSet("live");
		for (const char* req : {"config", "input", "output"})
			if (!cl.has(req) && !(live && std::string(req) == "input"))
				throw core::CommandLineError(std::string("missing --") + req);
		if (live && cl.has("input")) throw core::CommandLineError("--live and --input exclude each other");
		if (cl.flagSet("preview") && cl.flagSet("no-preview"))
			throw core::CommandLineError("--preview and --no-preview exclude each other");
		SlamRunOptions o;
		o.configPath = cl.get("config");
		o.input = cl.get("input");
		o.output = cl.get("output");
		o.groundTruth = cl.has("gt") ? cl.get("gt") : "";
		if (cl.has("mode")) o.modeOverride = runModeFromString(cl.get("mode"), "mode");
		if (cl.has("camera")) o.cameraOverride = cl.get("camera");
		if (cl.has("set"))
		{
			o.set = cl.get("set");
			try
			{
				parseOverrides(o.set, "--set");  // syntax errors are command-line errors
			}
			catch (const std::invalid_argument& e)
			{
				throw core::CommandLineError(e.what());
			}
		}
		if (cl.has("max-frames"))
		{
			const long n = cl.getInt("max-frames");
			if (n < 0) throw core::CommandLineError("--max-frames must be >= 0");
			o.maxFrames = static_cast<std::size_t>(n);
		}
		if (cl.has("first-frame"))
		{
			const long n = cl.getInt("first-frame");
			if (n < 0) throw core::CommandLineError("--first-frame must be >= 0");
			o.firstFrame = static_cast<std::size_t>(n);
		}
		if (cl.has("map")) o.mapFile = cl.get("map");
		if (cl.has("load-map")) o.loadMap = cl.get("load-map");
		o.localize = cl.flagSet("localize");
		if (o.localize && o.loadMap.empty()) throw core::CommandLineError("--localize needs --load-map FILE");
		if (live && o.firstFrame) throw core::CommandLineError("--first-frame is for recorded inputs, not --live");
		if (!o.loadMap.empty() && !o.mapFile.empty())
			throw core::CommandLineError(
				o.localize ? "--map and --load-map --localize exclude each other (localization does not record)"
						   : "--map and --load-map exclude each other (--load-map FILE without --localize records into FILE itself)");
		o.quiet = cl.flagSet("quiet");
		o.live = live;
		o.preview = live && !cl.flagSet("no-preview") && (cl.flagSet("preview") || LivePreview::displayAvailable());
		// Ctrl-C / SIGTERM end the frame loop; the outputs are still written (Interrupt.h).
		installInterruptHandlers();
		const auto r = runSlam(o);
		std::printf("frames %zu, tracked %zu, %.1f fps", r.frames, r.tracked, r.fps);
		if (r.ateRmse) std::printf(", ATE rmse %.4f m", *r.ateRmse);
		std::printf("\noutputs in %s\n", o.output.c_str());
		if (!r.error.empty())
		{
			// A failure in the run (input, processing) first, then files that could not be written.
			const bool runFailed = r.outputErrors.empty() || r.error != r.outputErrors.front();
			if (runFailed)
				std::fprintf(stderr, "keygrid-slam: error: %s (outputs of the %zu frames before it were written)\n", r.error.c_str(), r.frames);
			if (!r.outputErrors.empty())
				std::fprintf(stderr, "keygrid-slam: error: %s%s\n", r.outputErrors.front().c_str(),
							 r.outputErrors.size() > 1 ? (" (and " + std::to_string(r.outputErrors.size() - 1) + " more files not written)").c_str() : "");
			return 1;
		}
		// Shell convention for a run ended by a signal (130 = Ctrl-C), though it finished cleanly.
		if (r.interrupted) return 128 + (interruptSignal() ? interruptSignal() : SIGINT);
		return 0;
	});
}

}  // namespace keygrid::slam
