/** \file ism2d_sim_eval.cpp
 * keygrid_ism2d_sim_eval: accuracy of CISMOccupancyGrid2D against keygrid-sim's floor plan
 * (occupied-cell F1 and free-space accuracy at 5 cm).
 *
 *   keygrid_ism2d_sim_eval --sim SIMDIR [--every 10] [--input sparse|dense|both]
 *       [--poses gt|TRAJ.txt] [--align first|umeyama] [--slam-map map_2d.yaml] [--save PREFIX]
 *       [--scene SCENE.ini]
 *
 * SIMDIR is a keygrid-sim output (tum/, groundtruth.txt, floorplan.yaml). The sim world is
 * z-up with the floor at z = 0, so the grid's floor frame is the world (T_world_floor = I).
 *
 * Build mode (default): every N-th frame of SIMDIR/tum is a keyframe, inserted at the
 * ground-truth pose (--poses gt) or at the pose of a TUM trajectory such as keygrid-slam's
 * trajectory.txt, aligned to the sim world (--align first: by the first frame's ground-truth
 * pose, since the SLAM world is the first camera frame; umeyama: SE(3) least squares over all
 * frames). Inputs: sparse = 3D points from the measured depth at ORB keypoints (1000 per frame,
 * the stand-in for a keyframe's map points), dense = the keyframe's depth image.
 *
 * --slam-map: scores a map_2d.yaml written by keygrid-slam instead of building one: its floor
 * frame (in the SLAM world, from the yaml's keygrid comment line) is carried into the sim world
 * by the alignment of --poses, and the grid is resampled onto the floor plan's lattice.
 *
 * --scene (the INI SIMDIR was rendered from): also scores against the visible part of the floor
 * plan, i.e. the occupied cells a noise-free render at the keyframes' ground-truth poses sees
 * inside the obstacle height band (tests/maps/ISMSimEvaluation.h).
 *
 * Output: one line per run, "key value" pairs (F1, precision, recall, free accuracy, free
 * precision) at the 5 cm tolerance of evaluateOccupancy and with tolerance 0 (exact cell).
 */
#include <keygrid/core/FrameSource.h>
#include <keygrid/core/RgbdObservation.h>
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/eval/Alignment.h>
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <keygrid/maps/OccupancyGridMetrics.h>
#include <keygrid/sim/GroundTruthOccupancy.h>
#include <keygrid/sim/Renderer.h>
#include <keygrid/sim/Scene.h>
#include <mrpt/math/CMatrixFixed.h>

#include "ISMSimEvaluation.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

using namespace keygrid;
using keygrid::test::keypointPoints;
using keygrid::test::toFloorPlanGrid;

namespace
{
struct Args
{
	std::string sim, input{"both"}, poses{"gt"}, align{"first"}, slamMap, save, scene;
	int every{10};
	int features{1000};
};

Args parse(int argc, char** argv)
{
	Args a;
	for (int i = 1; i < argc; i++)
	{
		const std::string k = argv[i];
		auto val = [&]() -> std::string {
			if (i + 1 >= argc) throw std::invalid_argument("missing value after " + k);
			return argv[++i];
		};
		if (k == "--sim") a.sim = val();
		else if (k == "--every") a.every = std::stoi(val());
		else if (k == "--input") a.input = val();
		else if (k == "--poses") a.poses = val();
		else if (k == "--align") a.align = val();
		else if (k == "--slam-map") a.slamMap = val();
		else if (k == "--save") a.save = val();
		else if (k == "--scene") a.scene = val();
		else if (k == "--features") a.features = std::stoi(val());
		else if (k == "--help" || k == "-h")
		{
			std::cout << "see the comment at the top of tests/benchmarks/maps_ism/ism2d_sim_eval.cpp\n";
			std::exit(0);
		}
		else
			throw std::invalid_argument("unknown argument " + k);
	}
	if (a.sim.empty()) throw std::invalid_argument("--sim is required");
	if (a.every < 1) throw std::invalid_argument("--every must be >= 1");
	if (a.input != "sparse" && a.input != "dense" && a.input != "both")
		throw std::invalid_argument("--input must be sparse, dense or both");
	if (a.align != "first" && a.align != "umeyama") throw std::invalid_argument("--align must be first or umeyama");
	return a;
}

/** Pose at time t of a trajectory (exact timestamp match within 1 ms), or nullptr. */
const mrpt::poses::CPose3D* poseAt(const core::Trajectory& tr, double t)
{
	auto it = std::lower_bound(
		tr.begin(), tr.end(), t - 1e-3, [](const core::StampedPose& p, double v) { return p.t < v; });
	if (it == tr.end() || std::abs(it->t - t) > 1e-3) return nullptr;
	return &it->T_world_cam;
}

/** T_sim_est aligning an estimated trajectory to the ground truth. */
mrpt::poses::CPose3D alignTrajectory(const core::Trajectory& gt, const core::Trajectory& est, const std::string& how)
{
	std::vector<Eigen::Vector3d> x, y;
	const mrpt::poses::CPose3D* firstGt = nullptr;
	const mrpt::poses::CPose3D* firstEst = nullptr;
	for (const auto& e : est)
	{
		const auto* g = poseAt(gt, e.t);
		if (!g) continue;
		if (!firstGt)
		{
			firstGt = g;
			firstEst = &e.T_world_cam;
		}
		x.emplace_back(e.T_world_cam.x(), e.T_world_cam.y(), e.T_world_cam.z());
		y.emplace_back(g->x(), g->y(), g->z());
	}
	if (!firstGt) throw std::runtime_error("no common timestamps between the trajectories");
	if (how == "first") return *firstGt + (-*firstEst);
	return eval::rigidPose(eval::alignPointSets(x, y, false));
}

void printMetrics(const std::string& label, const maps::OccupancyMetrics& m, const maps::OccupancyMetrics& strict)
{
	std::printf(
		"%-40s F1 %.4f  P %.4f  R %.4f  free_acc %.4f (away from GT-occupied %.4f)  free_prec %.4f | exact-cell F1 %.4f"
		"  (est occ %zu, gt occ %zu, gt free observed %zu)\n",
		label.c_str(), m.f1, m.precision, m.recall, m.freeAccuracy, m.freeAccuracyAwayFromOccupied, m.freePrecision,
		strict.f1, m.estOccupied, m.gtOccupied, m.gtFreeObserved);
}

}  // namespace

int main(int argc, char** argv)
{
	try
	{
		const Args a = parse(argc, argv);
		const auto fp = sim::FloorPlan::load(a.sim + "/floorplan.yaml");
		const maps::FloorPlanGrid gt = toFloorPlanGrid(fp);
		const core::Trajectory gtTraj = core::readTumTrajectory(a.sim + "/groundtruth.txt");
		core::Trajectory poses = gtTraj;
		mrpt::poses::CPose3D T_sim_est;  // identity for gt poses
		if (a.poses != "gt")
		{
			const core::Trajectory est = core::readTumTrajectory(a.poses);
			T_sim_est = alignTrajectory(gtTraj, est, a.align);
			poses.clear();
			double sq = 0;
			for (const auto& e : est)
			{
				poses.push_back({e.t, T_sim_est + e.T_world_cam});
				if (const auto* g = poseAt(gtTraj, e.t))
					sq += mrpt::math::TPoint3D(poses.back().T_world_cam.translation() - g->translation()).sqrNorm();
			}
			std::printf("poses %s aligned by %s: translation RMSE vs ground truth %.4f m over %zu poses\n", a.poses.c_str(),
				a.align.c_str(), std::sqrt(sq / std::max<size_t>(1, est.size())), est.size());
		}
		maps::OccupancyMetricsOptions tol, exact;
		exact.matchTolerance = 0.0;

		if (!a.slamMap.empty())
		{
			const auto est = maps::TriStateGrid::loadRosMapServer(a.slamMap);
			if (!est.T_world_floor) throw std::runtime_error(a.slamMap + " has no keygrid T_world_floor line");
			const mrpt::poses::CPose3D T_sim_floor = T_sim_est + *est.T_world_floor;
			// Tilt of the estimated floor's normal against the sim's z axis.
			const auto R = T_sim_floor.getRotationMatrix();
			const double tiltDeg = std::acos(std::min(1.0, std::abs(R(2, 2)))) * 180.0 / M_PI;
			std::printf("estimated floor in the sim world: origin (%.3f, %.3f, %.3f) m, yaw %.2f deg, tilt %.2f deg\n",
				T_sim_floor.x(), T_sim_floor.y(), T_sim_floor.z(), T_sim_floor.yaw() * 180.0 / M_PI, tiltDeg);
			const auto res = maps::resampleTriState(est, T_sim_floor, gt);
			printMetrics("slam map_2d (" + a.slamMap + ")", maps::evaluateOccupancy(res, gt, tol),
				maps::evaluateOccupancy(res, gt, exact));
			return 0;
		}

		for (const std::string input : {"sparse", "dense"})
		{
			if (a.input != "both" && a.input != input) continue;
			CISMOccupancyGrid2D grid;  // default options: floor frame = sim world (z up, floor z = 0)
			auto src = core::openFrameSource(a.sim + "/tum");
			auto orb = cv::ORB::create(a.features);
			core::Frame f;
			size_t n = 0, kfs = 0, skipped = 0;
			std::optional<sim::Scene> scene;
			std::optional<sim::Renderer> renderer;
			if (!a.scene.empty())
			{
				scene.emplace(sim::Scene::loadFromFile(a.scene));
				renderer.emplace(*scene);
			}
			std::vector<uint8_t> visible;
			sim::RenderOutput perfect;
			double insertSec = 0;
			while (src->next(f))
			{
				const size_t index = n;
				if (n++ % static_cast<size_t>(a.every) != 0) continue;
				if (renderer)
				{
					const auto* Tgt = poseAt(gtTraj, f.timestamp);
					if (!Tgt) throw std::runtime_error("frame without ground-truth pose");
					renderer->render(*Tgt, scene->frameTime(index), perfect);
					const auto& o = grid.insertionOptions;
					test::markVisibleCells(visible, gt, perfect.depth, f.camera, *Tgt, o.obstacleMinHeight,
						o.obstacleMaxHeight, o.maxRange);
				}
				const auto* T = poseAt(poses, f.timestamp);
				if (!T)
				{
					skipped++;
					continue;
				}
				const auto obs = input == "dense" ? core::makeRgbdObservation(f) : nullptr;
				const auto pts = input == "sparse" ? keypointPoints(f, *T, orb) : std::vector<mrpt::math::TPoint3D>{};
				const auto t0 = std::chrono::steady_clock::now();
				if (obs)
					grid.insertKeyframeDepth(kfs, *T, *obs);
				else
					grid.insertKeyframePoints(kfs, *T, pts);
				insertSec += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
				kfs++;
			}
			const std::string label = input + ", every " + std::to_string(a.every) + " frames (" +
				std::to_string(kfs) + " kf), poses " + (a.poses == "gt" ? "gt" : "est");
			printMetrics(label, maps::evaluateOccupancy(grid, gt, tol), maps::evaluateOccupancy(grid, gt, exact));
			if (renderer)
			{
				const auto gtVisible = test::restrictToVisible(gt, visible);
				printMetrics("  same, visible part of the floor plan", maps::evaluateOccupancy(grid, gtVisible, tol),
					maps::evaluateOccupancy(grid, gtVisible, exact));
			}
			std::printf("  insertion %.2f ms per keyframe, %zu frames without pose\n",
				1e3 * insertSec / std::max<size_t>(1, kfs), skipped);
			if (!a.save.empty())
			{
				grid.saveAsImage(a.save + "_" + input + ".png");
				grid.saveAsRosMapServer(a.save + "_" + input + ".yaml");
			}
		}
		return 0;
	}
	catch (const std::exception& e)
	{
		std::fprintf(stderr, "keygrid_ism2d_sim_eval: error: %s\n", e.what());
		return 1;
	}
}
