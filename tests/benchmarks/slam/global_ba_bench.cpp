// The final global bundle adjustment on a stored map, timed and scored against ground truth.
//
// Record a run without its final step, then adjust the stored map as keygrid-slam's final step
// would, with the [refinement] / [mapping] options of an INI (plus --set overrides, checked as
// keygrid-slam checks them):
//
//   keygrid-slam --config config/sim.ini --input SIM/tum --output OUT --map map.kgmap
//       --set 'refinement.global_bundle_adjustment=false; refinement.refine_frames=false'
//   keygrid_global_ba_bench --session map.kgmap --config config/sim.ini --gt SIM/groundtruth.txt
//       [--set 'refinement.global_iterations=10'] [--repeat N]
//
// Prints one line per repetition: the problem's size, Ceres' time split (residuals and Jacobians,
// linear solver, the rest), iterations, and the keyframes' ATE before and after.
#include <keygrid/core/CommandLine.h>
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/eval/TrajectoryErrors.h>
#include <keygrid/sfm/LocalBundleAdjuster.h>
#include <keygrid/sfm/Tracker.h>
#include <keygrid/slam/FinalRefinement.h>
#include <keygrid/slam/SessionLoader.h>
#include <keygrid/slam/SlamConfig.h>
#include <keygrid/slam/apps/SlamApp.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <chrono>
#include <map>
#include <cstdio>
#include <iostream>

using namespace keygrid;

namespace
{
core::Trajectory keyframeTrajectory(const sfm::SparseMap& map)
{
	core::Trajectory out;
	for (const auto& [id, kf] : map.keyframes()) out.push_back({kf.timestamp, kf.T_world_cam});
	return out;
}
}  // namespace

int main(int argc, char** argv)
{
	try
	{
		core::CommandLine cl("keygrid_global_ba_bench", "The final global bundle adjustment of keygrid-slam on a stored map, timed and scored.");
		cl.option("session", "FILE", "session file recorded without the final step", true)
			.option("config", "CFG.ini", "the run's configuration", true)
			.option("gt", "GT.txt", "ground truth (TUM format)", true)
			.option("set", "SECTION.KEY=V[;...]", "overrides, as keygrid-slam --set")
			.option("repeat", "N", "repetitions, each on a fresh copy of the map", false, "1");
		if (!cl.parse(argc, argv)) return 0;
		const std::string text = slam::effectiveConfigText(cl.get("config"), cl.has("set") ? cl.get("set") : "");
		const auto cfg = slam::SlamConfig::FromConfig(mrpt::config::CConfigFileMemory(text), cl.get("config"));
		const auto gt = core::readTumTrajectory(cl.get("gt"));
		const auto session = store::SessionStore::Open(cl.get("session"));
		const auto K = session.meta().camera.pinhole();
		const long repeat = cl.getInt("repeat");
		for (long r = 0; r < repeat; r++)
		{
			sfm::SparseMap map;
			slam::loadSparseMap(session, map);
			const double ateBefore = eval::evaluateTrajectory(gt, keyframeTrajectory(map)).ate.rmse;
			std::map<sfm::KeyFrameId, mrpt::poses::CPose3D> before, after;
			for (const auto& [id, kf] : map.keyframes()) before[id] = kf.T_world_cam;
			const auto t0 = std::chrono::steady_clock::now();
			const auto ba = slam::finalBundleAdjustment(map, K, {}, cfg.refinement, cfg.mapping);
			const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
			const double ateAfter = eval::evaluateTrajectory(gt, keyframeTrajectory(map)).ate.rmse;
			for (const auto& [id, kf] : map.keyframes()) after[id] = kf.T_world_cam;
			const double moved = slam::largestDisplacement(before, after, cfg.refinement.mapReanchorDepth);
			const auto& rep = ba.report;
			std::printf(
				"keyframes %d landmarks %d (left out %d) observations %d | %.3f s (solver %.3f: evaluation %.3f, linear solver %.3f) "
				"iterations %d | cost %.1f -> %.1f | keyframe ATE %.2f -> %.2f mm | largest keyframe shift %.1f mm\n",
				rep.keyframes, rep.landmarks, rep.landmarksLeftOut, rep.observations, s, rep.solverSeconds, rep.evaluationSeconds,
				rep.linearSolverSeconds, rep.iterations, rep.initialCost, rep.finalCost, 1e3 * ateBefore, 1e3 * ateAfter, 1e3 * moved);
		}
		return 0;
	}
	catch (const std::exception& e)
	{
		std::cerr << "keygrid_global_ba_bench: error: " << e.what() << "\n";
		return 1;
	}
}
