#include <keygrid/core/CommandLine.h>
#include <keygrid/eval/TrajectoryErrors.h>
#include <keygrid/slam/apps/AppRunner.h>
#include <keygrid/slam/apps/EvalApp.h>
#include <keygrid/slam/apps/Grid3DEvaluation.h>
#include <keygrid/slam/apps/MapEvaluation.h>
#include <keygrid/core/AtomicOutput.h>
#include <mrpt/math/CMatrixFixed.h>

#include <iostream>

namespace keygrid::slam
{
namespace
{
/** The trajectory JSON object with the map's fields appended. */
std::string mergeJson(const std::string& trajectoryJson, const std::string& mapFields)
{
	const auto close = trajectoryJson.find_last_of('}');
	auto end = trajectoryJson.find_last_not_of(" \n", close - 1);
	return trajectoryJson.substr(0, end + 1) + ",\n" + mapFields + "\n}\n";
}

/** keygrid-eval's options and flags. */
core::CommandLine evalCommandLine()
{
	core::CommandLine cl(
		"keygrid-eval",
		"Evaluates an estimated TUM trajectory against ground truth: associates poses by\n"
		"timestamp, aligns positions (SE(3) Horn/Umeyama, or Sim(3) with --sim3), and reports\n"
		"the absolute trajectory error (ATE) and the relative pose error (RPE) per second.\n"
		"With --map and --floorplan it also scores keygrid-slam's 2D grid against keygrid-sim's\n"
		"floor plan, carried into the ground-truth world by the same alignment: hazard cells\n"
		"(obstacles called free), obstacle recall over the boundary cells the cameras saw,\n"
		"obstacle precision, free-space F1, the floor estimate's error; --overlay draws the\n"
		"map over the plan (colours: doc/maps-ism2d.md).\n"
		"With --grid3d and --voxels it scores keygrid-slam's 3D grid (map_3d.bt) against\n"
		"keygrid-sim's true occupied voxels, carried over by the same alignment (SE(3), or\n"
		"Sim(3) with --sim3): occupied-voxel precision, recall over the true voxels the keyframe\n"
		"cameras saw (--scene, --keyframes, --voxel-max-range), true voxels called free and the\n"
		"hazards among them (no map voxel within --tolerance). Both maps may be scored at once.");
	cl.option("gt", "GT.txt", "ground-truth trajectory (TUM format)", true)
		.option("est", "EST.txt", "estimated trajectory (TUM format)", true)
		.option("json", "OUT.json", "also write the results as JSON (keys ate_rmse_m, rpe_trans_m_per_s, rpe_rot_deg_per_s, matched, ...; map_* with --map, grid3d_* with --grid3d)")
		.option("max-dt", "SECONDS", "largest timestamp difference for a match", false, "0.02")
		.option("delta", "SECONDS", "RPE time step", false, "1.0")
		.option("map", "MAP_2D.yaml", "keygrid-slam's 2D grid (its first line holds the floor pose) to score; needs --floorplan")
		.option("floorplan", "PLAN.yaml", "keygrid-sim's ground-truth floor plan (floorplan.yaml)")
		.option("scene", "SCENE.ini", "with --keyframes: render the scene at the keyframes' ground-truth poses to know which cells (voxels) the cameras saw")
		.option("keyframes", "KF.txt", "keyframe timestamps (keygrid-slam's keyframes.txt), with --scene")
		.option("overlay", "OUT.png", "write the map laid over the floor plan (occupied / free / missed / hazard / false obstacle)")
		.option("tolerance", "M", "occupied cells (voxels) match within this distance", false, "0.05")
		.option("max-range", "M", "horizontal range of the cameras' view for --map with --scene", false, "4.5")
		.option("grid3d", "MAP_3D.bt", "keygrid-slam's 3D grid (OctoMap binary; its header holds the floor pose) to score; needs --voxels")
		.option("voxels", "VOXELS.txt", "keygrid-sim's ground-truth occupied voxels (occupancy_voxels.txt)")
		.option("voxel-max-range", "M", "distance from the camera within which a rendered surface counts as seen, for --grid3d with --scene", false, "4.0")
		.option("map-run-gt", "GT1.txt", "with --map-run-est: measure --est in a stored map's frame, fixed by the mapping run's poses (orientations and positions) against this ground truth (localization runs: not re-aligned)")
		.option("map-run-est", "EST1.txt", "the mapping run's trajectory (keygrid-slam --map), with --map-run-gt")
		.flag("sim3", "align with scale (for monocular or scale-drifting estimates)")
		.flag("skip-bad-lines", "skip malformed lines (reported) instead of failing")
		.flag("quiet", "no progress output");
	return cl;
}

/** The alignment and error options (--max-dt, --delta, --sim3), checked. */
eval::TrajectoryErrorOptions trajectoryErrorOptions(const core::CommandLine& cl)
{
	eval::TrajectoryErrorOptions opts;
	opts.maxDt = cl.getDouble("max-dt");
	opts.rpeDelta = cl.getDouble("delta");
	opts.withScale = cl.flagSet("sim3");
	std::string why;
	if (!opts.isValid(&why)) throw core::CommandLineError(why);
	return opts;
}

/** The map scoring options of --map (which needs --floorplan); without
 * --map, its companion options are command-line errors. */
MapEvaluationOptions mapEvaluationOptions(const core::CommandLine& cl, const eval::TrajectoryErrorOptions& opts)
{
	MapEvaluationOptions mo;
	if (!cl.has("map"))
	{
		for (const std::string k : {"floorplan", "overlay"})
			if (cl.has(k)) throw core::CommandLineError("--" + k + " needs --map");
		if (!cl.has("grid3d"))
			for (const std::string k : {"scene", "keyframes"})
				if (cl.has(k)) throw core::CommandLineError("--" + k + " needs --map or --grid3d");
		return mo;
	}
	if (!cl.has("floorplan")) throw core::CommandLineError("--map needs --floorplan");
	if (cl.has("scene") != cl.has("keyframes")) throw core::CommandLineError("--scene and --keyframes go together");
	mo.mapYaml = cl.get("map");
	mo.floorPlanYaml = cl.get("floorplan");
	mo.scenePath = cl.has("scene") ? cl.get("scene") : "";
	mo.keyframesPath = cl.has("keyframes") ? cl.get("keyframes") : "";
	mo.overlayPath = cl.has("overlay") ? cl.get("overlay") : "";
	mo.metrics.matchTolerance = cl.getDouble("tolerance");
	mo.visibility.maxRange = cl.getDouble("max-range");
	mo.maxDt = opts.maxDt;
	mo.progress = !cl.flagSet("quiet");
	std::string why;
	if (!mo.metrics.isValid(&why)) throw core::CommandLineError("--tolerance: " + why);
	if (!mo.visibility.isValid(&why)) throw core::CommandLineError("--max-range: " + why);
	return mo;
}

/** The 3D grid scoring options of --grid3d (which needs --voxels); without --grid3d, --voxels
 * is a command-line error. */
Grid3DEvaluationOptions grid3dEvaluationOptions(const core::CommandLine& cl, const eval::TrajectoryErrorOptions& opts)
{
	Grid3DEvaluationOptions go;
	if (!cl.has("grid3d"))
	{
		if (cl.has("voxels")) throw core::CommandLineError("--voxels needs --grid3d");
		return go;
	}
	if (!cl.has("voxels")) throw core::CommandLineError("--grid3d needs --voxels");
	if (cl.has("scene") != cl.has("keyframes")) throw core::CommandLineError("--scene and --keyframes go together");
	go.gridBt = cl.get("grid3d");
	go.voxelsPath = cl.get("voxels");
	go.scenePath = cl.has("scene") ? cl.get("scene") : "";
	go.keyframesPath = cl.has("keyframes") ? cl.get("keyframes") : "";
	go.metrics.matchTolerance = cl.getDouble("tolerance");
	go.maxRange = cl.getDouble("voxel-max-range");
	go.maxDt = opts.maxDt;
	go.progress = !cl.flagSet("quiet");
	std::string why;
	if (!go.metrics.isValid(&why)) throw core::CommandLineError("--tolerance: " + why);
	if (!go.isValid(&why)) throw core::CommandLineError("--voxel-max-range: " + why);
	return go;
}
}  // namespace

int EvalApp::run(int argc, const char* const* argv)
{
	return runApp("keygrid-eval", [&] {
		core::CommandLine cl = evalCommandLine();
		if (!cl.parse(argc, argv)) return 0;
		eval::TrajectoryErrorOptions opts = trajectoryErrorOptions(cl);
		const bool mapMode = cl.has("map");
		const MapEvaluationOptions mo = mapEvaluationOptions(cl, opts);
		const bool grid3dMode = cl.has("grid3d");
		const Grid3DEvaluationOptions go = grid3dEvaluationOptions(cl, opts);

		core::TrajectoryReadOptions ro;
		ro.skipBadLines = cl.flagSet("skip-bad-lines");
		std::vector<core::TextLineIssue> issues;
		const auto gt = core::readTumTrajectory(cl.get("gt"), ro, &issues);
		const auto est = core::readTumTrajectory(cl.get("est"), ro, &issues);
		for (const auto& is : issues) std::cerr << "keygrid-eval: skipped " << is.str() << "\n";
		if (cl.has("map-run-gt") != cl.has("map-run-est")) throw core::CommandLineError("--map-run-gt and --map-run-est go together");
		if (cl.has("map-run-gt"))
		{
			const auto gt1 = core::readTumTrajectory(cl.get("map-run-gt"), ro, &issues);
			const auto est1 = core::readTumTrajectory(cl.get("map-run-est"), ro, &issues);
			opts.fixedAlignment = eval::alignTrajectoryPoses(gt1, est1, opts.maxDt);
		}
		const auto res = eval::evaluateTrajectory(gt, est, opts);
		std::cout << res.toText();
		std::string json = res.toJson();
		if (mapMode)
		{
			const auto m = evaluateMapAgainstFloorPlan(mo, res.alignment, gt);
			std::cout << m.toText();
			if (!mo.overlayPath.empty()) std::cout << "overlay: " << mo.overlayPath << "\n";
			json = mergeJson(json, m.jsonFields());
		}
		if (grid3dMode)
		{
			const auto g = evaluateGrid3DAgainstVoxels(go, res.alignment, gt);
			std::cout << g.toText();
			json = mergeJson(json, g.jsonFields());
		}
		if (cl.has("json")) core::writeFileAtomically(cl.get("json"), json);
		return 0;
	});
}

}  // namespace keygrid::slam
