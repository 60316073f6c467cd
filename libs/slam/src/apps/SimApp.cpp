#include <keygrid/core/CommandLine.h>
#include <keygrid/core/ProgressBar.h>
#include <keygrid/sim/Augment.h>
#include <keygrid/sim/Scene.h>
#include <keygrid/sim/SequenceWriter.h>
#include <keygrid/slam/Interrupt.h>
#include <keygrid/slam/apps/AppRunner.h>
#include <keygrid/slam/apps/BatchExperiment.h>
#include <keygrid/slam/apps/SimApp.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/system/filesystem.h>

#include <csignal>
#include <cstdio>
#include <iostream>
#include <stdexcept>

namespace keygrid::slam
{
namespace
{
/** keygrid-sim's options and flags. */
core::CommandLine simCommandLine()
{
	core::CommandLine cl(
		"keygrid-sim",
		"Renders a synthetic RGB-D sequence (Kinect-like noise, exact ground truth) from a\n"
		"scene INI into DIR/sequence.rawlog, DIR/groundtruth.txt, DIR/tum/ (TUM layout),\n"
		"DIR/occupancy_voxels.txt and DIR/floorplan.pgm/.yaml. With --augment TUM_DIR it\n"
		"renders the scene's objects into a real TUM sequence at its ground-truth poses\n"
		"instead (occlusion against the real depth; tum/mask/ marks the inserted pixels).\n"
		"--set 'output.sensor=monocular' writes the images alone (a rawlog of\n"
		"CObservationImage, tum/ with rgb.txt only). See doc/simulator.md.");
	cl.option("scene", "SCENE.ini", "scene description (e.g. config/sim/room_loop.ini)", true)
		.option("output", "DIR", "output folder (created if needed)", true)
		.option(
			"frames", "N", "number of frames, overriding [scene] frames (--augment: at most N)",
			false, "from the scene")
		.option("seed", "S", "master seed, overriding [scene] seed", false, "from the scene")
		.option("threads", "N", "render threads (0 = all cores)", false, "0")
		.option(
			"voxel-resolution", "M", "ground-truth voxel size, overriding [output] (0 = none)",
			false, "from the scene, else 0.05")
		.option(
			"floorplan-resolution", "M", "floor-plan cell size, overriding [output] (0 = none)",
			false, "from the scene, else 0.05")
		.option(
			"augment", "TUM_DIR",
			"real TUM folder with groundtruth.txt to render the objects into")
		.option(
			"camera", "PRESET|FILE.ini", "camera of the --augment folder", false,
			"from the folder")
		.option(
			"set", "SECTION.KEY=V[;...]",
			"override scene keys, e.g. 'sensor.disparity_distortion=0.3' (unknown keys are "
			"errors)")
		.flag("no-noise", "exact depth and images: [sensor] noise = false")
		.flag("mask", "also write DIR/tum/mask/ (255 = dynamic object pixel)")
		.flag("quiet", "no progress output");
	return cl;
}

/** The scene file's text with the --set overrides applied. The INI is only read: overrides
 * go to an in-memory copy. (An mrpt::config::CConfigFile would write them back into the
 * user's scene file on destruction; discardSavingChanges() is undone by any later write().) */
std::string sceneText(const core::CommandLine& cl, const std::string& scenePath)
{
	if (!mrpt::system::fileExists(scenePath))
		throw std::runtime_error("scene file '" + scenePath + "' does not exist");
	std::string text = mrpt::io::file_get_contents(scenePath);
	if (!cl.has("set")) return text;
	try
	{
		return applyOverrides(text, parseOverrides(cl.get("set"), "--set"));
	}
	catch (const std::invalid_argument& e)
	{
		throw core::CommandLineError(e.what());
	}
}

/** The [output] section with the --mask, --voxel-resolution and --floorplan-resolution
 * overrides. */
sim::OutputOptions outputOptions(const core::CommandLine& cl, const mrpt::config::CConfigFileMemory& cfg)
{
	sim::OutputOptions out;
	if (cfg.sectionExists("output")) out.loadFromConfigFile(cfg, "output");
	if (cl.flagSet("mask")) out.writeMask = true;
	for (const std::string key : {"voxel-resolution", "floorplan-resolution"})
	{
		if (!cl.has(key)) continue;
		const double r = cl.getDouble(key);
		if (!(r == 0 || (r >= 0.005 && r <= 10)))
			throw core::CommandLineError("--" + key + " must be 0 or in [0.005, 10] m");
		(key == "voxel-resolution" ? out.voxelResolution : out.floorPlanResolution) = r;
	}
	return out;
}

/** --augment: renders the scene's objects into the real TUM sequence, with the mask. */
int augment(const core::CommandLine& cl, const sim::Scene& scene, sim::OutputOptions out, long frames, long threads)
{
	const std::string dir = cl.get("output");
	sim::AugmentOptions ao;
	if (cl.has("camera")) ao.camera = cl.get("camera");
	if (frames > 0) ao.maxFrames = static_cast<std::size_t>(frames);
	out.writeMask = true;
	core::ProgressBar bar("augmenting", 0, !cl.flagSet("quiet"));
	const sim::AugmentSummary s = sim::augmentTumSequence(
		scene, cl.get("augment"), dir, out, ao,
		[&](std::size_t done, std::size_t) { bar.update(done); },
		static_cast<unsigned>(threads));
	bar.finish();
	char line[512];
	std::snprintf(
		line, sizeof(line),
		"wrote %zu augmented frames to %s in %.1f s (%zu skipped without ground truth); "
		"inserted pixels %.1f %%\n",
		s.frames, dir.c_str(), s.seconds, s.skippedNoPose, 100.0 * s.insertedPixelFraction);
	std::cout << line;
	return 0;
}

/** Renders the sequence; Ctrl-C / SIGTERM: the frames rendered so far are written as a
 * shorter sequence and the exit code says which signal ended it. */
int render(const core::CommandLine& cl, const sim::Scene& scene, const sim::OutputOptions& out, long threads)
{
	const std::string dir = cl.get("output");
	core::ProgressBar bar("rendering", scene.options.frames, !cl.flagSet("quiet"));
	installInterruptHandlers();
	const sim::SequenceSummary s = sim::writeSequence(
		scene, dir, out, [&](std::size_t done, std::size_t) { bar.update(done); },
		static_cast<unsigned>(threads), [] { return interruptRequested(); });
	bar.finish();
	char line[512];
	std::snprintf(
		line, sizeof(line),
		"wrote %zu frames of scene '%s' to %s in %.1f s (render %.1f fps); camera max %.2f "
		"m/s, "
		"%.1f deg/s; ground truth: %zu voxels, %zu floor-plan cells; dynamic pixels %.1f %%\n",
		s.frames, scene.options.name.c_str(), dir.c_str(), s.seconds,
		s.renderSeconds > 0 ? s.frames / s.renderSeconds : 0.0, s.maxSpeed, s.maxTurnRateDeg,
		s.voxels, s.floorPlanCells, 100.0 * s.dynamicPixelFraction);
	std::cout << line;
	if (s.stopped)
	{
		std::cerr << "keygrid-sim: interrupted after " << s.frames << " of " << scene.options.frames << " frames (written)\n";
		return 128 + (interruptSignal() ? interruptSignal() : SIGINT);
	}
	return 0;
}
}  // namespace

int SimApp::run(int argc, const char* const* argv)
{
	return runApp("keygrid-sim", [&] {
		core::CommandLine cl = simCommandLine();
		if (!cl.parse(argc, argv)) return 0;
		long frames = 0;
		if (cl.has("frames"))
		{
			frames = cl.getInt("frames");
			if (frames < 1) throw core::CommandLineError("--frames must be >= 1");
		}
		const long threads = cl.getInt("threads");
		if (threads < 0 || threads > 256)
			throw core::CommandLineError("--threads must be in [0, 256]");

		const std::string scenePath = cl.get("scene");
		mrpt::config::CConfigFileMemory cfg(sceneText(cl, scenePath));
		if (cl.has("seed"))
		{
			const long seed = cl.getInt("seed");
			if (seed < 0) throw core::CommandLineError("--seed must be >= 0");
			cfg.write("scene", "seed", std::to_string(seed));  // textures derive from it too
		}
		sim::Scene scene =
			sim::Scene::loadFromConfig(cfg, scenePath, static_cast<unsigned>(frames));
		if (cl.flagSet("no-noise")) scene.sensor.noise = false;
		const sim::OutputOptions out = outputOptions(cl, cfg);
		return cl.has("augment") ? augment(cl, scene, out, frames, threads) : render(cl, scene, out, threads);
	});
}

}  // namespace keygrid::slam
