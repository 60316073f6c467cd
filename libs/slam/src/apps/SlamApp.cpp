/** \file SlamApp.cpp
 * keygrid-slam's command line: options, their checks, the information flags, and the summary
 * and exit code of a run (the run itself: SlamRun.cpp).
 */
#include <keygrid/core/CommandLine.h>
#include <keygrid/slam/Interrupt.h>
#include <keygrid/slam/IniReference.h>
#include <keygrid/slam/LivePreview.h>
#include <keygrid/slam/apps/AppRunner.h>
#include <keygrid/slam/apps/BatchExperiment.h>
#include <keygrid/slam/apps/SlamApp.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <csignal>
#include <cstdio>
#include <iostream>

namespace keygrid::slam
{
namespace
{
/** keygrid-slam's options and flags. */
core::CommandLine slamCommandLine()
{
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
	return cl;
}

/** --ini-reference and --dump-config: prints what they ask for; true when one was given (the
 * program ends there). */
bool printedInformation(const core::CommandLine& cl)
{
	if (cl.flagSet("ini-reference"))
	{
		std::cout << iniReferenceMarkdown();
		return true;
	}
	if (!cl.flagSet("dump-config")) return false;
	if (cl.has("set") && !cl.has("config")) throw core::CommandLineError("--set needs --config");
	const SlamConfig c = cl.has("config") ? SlamConfig::FromConfig(
		mrpt::config::CConfigFileMemory(effectiveConfigText(cl.get("config"), cl.has("set") ? cl.get("set") : "")),
		cl.get("config")) : SlamConfig();
	mrpt::config::CConfigFileMemory mem;
	c.saveToConfigFile(mem);
	std::cout << "# keygrid-slam effective configuration\n" << mem.getContent();
	return true;
}

/** The value of count option `name` (--max-frames, --first-frame), which must be >= 0. */
std::size_t countOption(const core::CommandLine& cl, const std::string& name)
{
	const long n = cl.getInt(name);
	if (n < 0) throw core::CommandLineError("--" + name + " must be >= 0");
	return static_cast<std::size_t>(n);
}

/** The run's options from the command line; missing options and options that exclude each
 * other are command-line errors. */
SlamRunOptions runOptionsFrom(const core::CommandLine& cl)
{
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
	if (cl.has("max-frames")) o.maxFrames = countOption(cl, "max-frames");
	if (cl.has("first-frame")) o.firstFrame = countOption(cl, "first-frame");
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
	return o;
}

/** Prints the run's summary line (stdout) and its errors (stderr); returns the exit code. */
int summarize(const SlamRunResult& r, const std::string& output)
{
	std::printf("frames %zu, tracked %zu, %.1f fps", r.frames, r.tracked, r.fps);
	if (r.ateRmse) std::printf(", ATE rmse %.4f m", *r.ateRmse);
	std::printf("\noutputs in %s\n", output.c_str());
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
}
}  // namespace

int SlamApp::run(int argc, const char* const* argv)
{
	return runApp("keygrid-slam", [&] {
		core::CommandLine cl = slamCommandLine();
		if (!cl.parse(argc, argv)) return 0;
		if (printedInformation(cl)) return 0;
		const SlamRunOptions o = runOptionsFrom(cl);
		// Ctrl-C / SIGTERM end the frame loop; the outputs are still written (Interrupt.h).
		installInterruptHandlers();
		return summarize(runSlam(o), o.output);
	});
}

}  // namespace keygrid::slam
