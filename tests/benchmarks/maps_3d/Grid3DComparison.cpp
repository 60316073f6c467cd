/** \file Grid3DComparison.cpp
 * Side-by-side comparison, in one run, of depth-frame integration into
 *   - keygrid::CSubmappedOccupancyGrid3D (every pixel, DDA, per-frame duplicate suppression),
 *   - OctoMap 1.9.7 OcTree::insertPointCloud(discretize = true),
 *   - MRPT COccupancyGridMap3D::insertObservation (decimation_3d_range = 1),
 * on real Kinect frames: a TUM folder with ground-truth poses and MRPT's tests_rgbd.rawlog.
 * All use the same voxel size, max range and (keygrid / OctoMap) the same hit / miss / clamp
 * log-odds and the same undistorted end points. Reports time per frame, occupied-voxel agreement
 * with OctoMap and memory per m^3 of observed space.
 *
 * Usage: keygrid_bench_maps_3d [--tum DIR] [--rawlog FILE] [--frames N] [--stride K]
 *        [--res M] [--max-range M] [--no-mrpt] [--repeat R] [--morph-window M]
 *        [--morph-k K1,K2,..] (also morph with at most K keyframes per block, each K)
 */
#include <keygrid/core/FrameConventions.h>
#include <keygrid/core/RgbdObservation.h>
#include <keygrid/core/TumFrameSource.h>
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/eval/Alignment.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <mrpt/maps/COccupancyGridMap3D.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/system/CTicTac.h>
#include <mrpt/system/filesystem.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <iostream>
#include <string>
#include <vector>

using namespace keygrid;
using mrpt::poses::CPose3D;

namespace
{
struct Args
{
	std::string tum = std::string(KEYGRID_SOURCE_DIR) + "/../shared/data/tum_fr1_rpy_first250";
	std::string rawlog = "/usr/share/mrpt/datasets/tests_rgbd.rawlog";
	unsigned frames = 30, stride = 8, repeat = 3;
	double res = 0.05, maxRange = 4.0;
	bool mrpt = true;
	double morphWindow = -1;  // < 0: the MorphingOptions default
	std::vector<unsigned> morphK;  // --morph-k: also morph with these maxKeyframesPerBlock
	double conflictTravel = -1;  // < 0: the ConflictOptions default
	double driftM = 0.2, driftDeg = 6.0;  // synthetic drift at the last frame
	std::string gtVoxels;  // keygrid-sim occupancy_voxels.txt (optional)
	std::vector<std::string> scoreBt;  // keygrid-slam output dirs: score DIR/map_3d.bt vs the sim GT
	std::string simDir;
	std::string camera;  // camera preset or INI (optional; TUM folders guess it otherwise)
	bool verbose = false;  // per-keyframe evidence of the drifted run
	bool profile = false;  // time castFrame / evaluateFrame / apply separately
};

/** One frame as the three mappers see it. */
struct BenchFrame
{
	cv::Mat depth;  // [m]
	core::RgbdCamera cam;
	CPose3D T_world_cam;
	octomap::Pointcloud cloud;  // world end points of the valid pixels (undistorted)
	mrpt::obs::CObservation3DRangeScan::Ptr obs;  // for MRPT; sensorPose = T_world_depth
};

void buildCloud(BenchFrame& f)
{
	PixelRayTable rays;
	rays.update(f.cam);
	for (unsigned v = 0; v < f.cam.height; ++v)
	{
		const float* xy = rays.row(v);
		for (unsigned u = 0; u < f.cam.width; ++u)
		{
			const float d = f.depth.at<float>(int(v), int(u));
			if (!(d > 0)) continue;
			const auto p = f.T_world_cam.composePoint(mrpt::math::TPoint3D(xy[2 * u] * d, xy[2 * u + 1] * d, d));
			f.cloud.push_back(float(p.x), float(p.y), float(p.z));
		}
	}
}

struct Result
{
	double msPerFrame{0};
	std::size_t occupied{0}, known{0};
	double bytes{0}, observedM3{0};
};

double agreement(const VoxelBlockGrid& g, const octomap::OcTree& tree, std::size_t& ours,
	std::size_t& theirs, std::size_t& both)
{
	ours = theirs = both = 0;
	g.forEachKnown([&](const VoxelIndex& v, const Voxel& x) {
		if (x.logOdds <= 0) return;
		++ours;
		const octomap::OcTreeNode* n = tree.search(
			octomap::OcTreeKey(v.x + 32768, v.y + 32768, v.z + 32768));
		both += (n && tree.isNodeOccupied(n)) ? 1 : 0;
	});
	double occVox = 0;
	for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it)
		if (tree.isNodeOccupied(*it))
		{
			const double s = std::pow(2.0, 16 - int(it.getDepth()));
			occVox += s * s * s;
		}
	theirs = std::size_t(occVox);
	return double(both) / double(ours + theirs - both);  // Jaccard
}

double octreeKnownVolume(const octomap::OcTree& tree)
{
	double v = 0;
	for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) v += std::pow(it.getSize(), 3);
	return v;
}

/** Wall clock and CPU time of the calling thread [s] (CPU time is what a single-threaded
 * mapper costs even when other processes share the cores). */
struct Clock
{
	double wall0{now()}, cpu0{cpu()};
	static double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
	static double cpu()
	{
		timespec ts{};
		clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
		return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
	}
	void restart() { wall0 = now(), cpu0 = cpu(); }
	double wall() const { return now() - wall0; }
	double cpuTime() const { return cpu() - cpu0; }
};
/** Steady-state [ms per frame] over frames 2..N: wall and calling-thread CPU time. */
struct FrameTime
{
	double wallMs{1e300}, cpuMs{1e300};
	void keepMin(const FrameTime& o) { wallMs = std::min(wallMs, o.wallMs), cpuMs = std::min(cpuMs, o.cpuMs); }
};
template <class InsertFrame>
FrameTime timeFrames(std::size_t n, InsertFrame&& insert)
{
	Clock c;
	double w1 = 0, c1 = 0;
	for (std::size_t i = 0; i < n; ++i)
	{
		insert(i);
		if (i == 0) w1 = c.wall(), c1 = c.cpuTime();  // the first frame builds caches: excluded
	}
	const double k = n > 1 ? 1000.0 / double(n - 1) : 1000.0;
	if (n <= 1) return {k * w1, k * c1};
	return {k * (c.wall() - w1), k * (c.cpuTime() - c1)};
}

/** Timing breakdown of keygrid's integration steps (the three calls insertDepthFrame makes),
 * steady state (frames 2..N), for 1 thread and all threads. */
void profileSteps(const std::vector<BenchFrame>& frames, const Args& a)
{
	if (frames.size() < 2) return;
	for (unsigned threads : {1u, 0u})
	{
		DepthIntegrationOptions io;
		io.maxRange = a.maxRange;
		io.minRange = 0.0;
		io.threads = threads;
		DepthFrameIntegrator integ(io);
		VoxelBlockGrid grid(a.res);
		ConflictOptions co;
		double tCast = 0, tEval = 0, tApply = 0, cpuCast = 0;
		std::size_t castRays = 0, visits = 0, chunks = 0;
		for (std::size_t i = 0; i < frames.size(); ++i)
		{
			Clock t;
			const auto upd = integ.castFrame(frames[i].depth, frames[i].cam, frames[i].T_world_cam, a.res);
			const double c = t.wall(), cc = t.cpuTime();
			t.restart();
			const auto ev = evaluateFrame(grid, upd, 0.0, co, threads);
			const double e = t.wall();
			t.restart();
			integ.apply(grid, upd, 0.0);
			const double p = t.wall();
			(void)ev;
			if (i == 0) continue;
			tCast += c, tEval += e, tApply += p, cpuCast += cc;
			castRays += upd.castRays, visits += upd.voxelVisits, chunks += upd.chunks.size();
		}
		const double n = double(frames.size() - 1);
		std::printf("profile (%s, wall): castFrame %.3f ms (calling thread CPU %.3f ms), evaluateFrame %.3f ms, apply %.3f ms "
					"per frame; %.0f rays cast, %.0f voxel visits, %.0f chunks per frame\n",
			threads == 1 ? "1 thread" : "all threads", 1e3 * tCast / n, 1e3 * cpuCast / n, 1e3 * tEval / n, 1e3 * tApply / n,
			double(castRays) / n, double(visits) / n, double(chunks) / n);
	}
}

void runComparison(const std::string& label, const std::vector<BenchFrame>& frames, const Args& a)
{
	std::printf("\n=== %s: %zu frame(s), %.0f mm voxels, max range %.1f m, every pixel ===\n",
		label.c_str(), frames.size(), a.res * 1000, a.maxRange);
	if (frames.empty()) return;
	if (a.profile) profileSteps(frames, a);

	// keygrid, all cores and one core; OctoMap. Each `repeat` times, the fastest run kept.
	auto runKeygrid = [&](unsigned threads, CSubmappedOccupancyGrid3D& m) {
		m.setResolution(a.res);
		m.insertionOptions.integration.maxRange = a.maxRange;
		m.insertionOptions.integration.minRange = 0.0;
		m.insertionOptions.integration.threads = threads;
		// One consistent trajectory (ground truth): keep a single submap for the comparison.
		m.insertionOptions.conflict.conflictMinVoxels = 1e12;
		double travelled = 0;
		return timeFrames(frames.size(), [&](std::size_t i) {
			if (i > 0) travelled += frames[i].T_world_cam.distanceTo(frames[i - 1].T_world_cam);
			m.insertDepthFrame(frames[i].depth, frames[i].cam, frames[i].T_world_cam, travelled, i);
		});
	};
	auto runOctomap = [&](octomap::OcTree& tree) {
		return timeFrames(frames.size(), [&](std::size_t i) {
			const auto& f = frames[i];
			tree.insertPointCloud(f.cloud,
				octomap::point3d(float(f.T_world_cam.x()), float(f.T_world_cam.y()), float(f.T_world_cam.z())),
				a.maxRange, false, true);
		});
	};
	CSubmappedOccupancyGrid3D kg;
	octomap::OcTree tree(a.res);
	FrameTime kgT, kg1T, octoT;
	for (unsigned r = 0; r < a.repeat; ++r)
	{
		CSubmappedOccupancyGrid3D m, m1;
		octomap::OcTree t(a.res);
		kgT.keepMin(runKeygrid(0, m));
		kg1T.keepMin(runKeygrid(1, m1));
		octoT.keepMin(runOctomap(t));
		if (r == 0) kg = m, tree.swapContent(t);
	}
	const double kgMs = kgT.wallMs, kg1Ms = kg1T.wallMs, octoMs = octoT.wallMs;
	const VoxelBlockGrid& g = kg.submap(0).grid;

	// MRPT COccupancyGridMap3D over the bounding box of the cameras +- max range.
	double mrptMs = -1, mrptBytes = 0;
	if (a.mrpt)
	{
		mrpt::math::TPoint3D lo(1e9, 1e9, 1e9), hi(-1e9, -1e9, -1e9);
		for (const auto& f : frames)
		{
			lo = {std::min(lo.x, f.T_world_cam.x()), std::min(lo.y, f.T_world_cam.y()), std::min(lo.z, f.T_world_cam.z())};
			hi = {std::max(hi.x, f.T_world_cam.x()), std::max(hi.y, f.T_world_cam.y()), std::max(hi.z, f.T_world_cam.z())};
		}
		const double R = a.maxRange + 0.2;
		mrpt::maps::COccupancyGridMap3D grid(
			{lo.x - R, lo.y - R, lo.z - R}, {hi.x + R, hi.y + R, hi.z + R}, float(a.res));
		grid.insertionOptions.decimation_3d_range = 1;
		grid.insertionOptions.maxDistanceInsertion = float(a.maxRange);
		mrpt::system::CTicTac t;
		double first = 0;
		for (std::size_t i = 0; i < frames.size(); ++i)
		{
			grid.insertObservation(*frames[i].obs);
			if (i == 0) first = t.Tac();
		}
		mrptMs = frames.size() > 1 ? 1000.0 * (t.Tac() - first) / (frames.size() - 1) : 1000.0 * first;
		const auto& m = grid.m_grid;
		mrptBytes = double(m.getSizeX()) * m.getSizeY() * m.getSizeZ() * sizeof(int8_t);
	}

	std::size_t ours = 0, theirs = 0, both = 0;
	const double jac = agreement(g, tree, ours, theirs, both);
	const double voxM3 = a.res * a.res * a.res;
	const double ourObserved = g.numKnownVoxels() * voxM3;
	const double octoObserved = octreeKnownVolume(tree);

	PixelRayTable table;
	mrpt::system::CTicTac tt;
	table.update(frames.front().cam);
	std::printf("(excluded from the steady state: keygrid's one-off undistorted ray table, %.1f ms; "
				"OctoMap's point cloud is built outside its timing)\n", 1000.0 * tt.Tac());
	std::printf("%-44s %10s %10s %12s %12s\n", "integration (steady state, frames 2..N)", "ms/frame", "x keygrid",
		"CPU ms/frame", "CPU x kg(1t)");
	std::printf("%-44s %10.2f %10.2f %12s %12s\n", "keygrid CSubmappedOccupancyGrid3D (2 threads)", kgMs, 1.0, "-", "-");
	std::printf("%-44s %10.2f %10.2f %12.2f %12.2f\n", "keygrid CSubmappedOccupancyGrid3D (1 thread)", kg1Ms, kg1Ms / kgMs,
		kg1T.cpuMs, 1.0);
	std::printf("%-44s %10.2f %10.2f %12.2f %12.2f\n", "OctoMap 1.9.7 insertPointCloud(discretize)", octoMs, octoMs / kgMs,
		octoT.cpuMs, octoT.cpuMs / kg1T.cpuMs);
	std::printf("OctoMap / keygrid: wall %.2fx (2 threads), %.2fx (1 thread); CPU %.2fx (1 thread)\n", octoMs / kgMs,
		octoMs / kg1Ms, octoT.cpuMs / kg1T.cpuMs);
	if (a.mrpt)
		std::printf("%-44s %10.1f %10.2f\n", "MRPT COccupancyGridMap3D (decimation 1)", mrptMs, mrptMs / kgMs);
	std::printf("occupied voxels: keygrid %zu, OctoMap %zu, both %zu -> %.2f%% of OctoMap's, %.2f%% "
				"of keygrid's, Jaccard %.3f\n",
		ours, theirs, both, 100.0 * both / std::max<std::size_t>(theirs, 1),
		100.0 * both / std::max<std::size_t>(ours, 1), jac);
	std::printf("observed volume: keygrid %.2f m^3, OctoMap %.2f m^3\n", ourObserved, octoObserved);
	std::printf("memory: keygrid %.1f MB (%.0f kB per observed m^3, %.2f B per allocated voxel, %zu "
				"blocks); OctoMap %.1f MB (%.0f kB per observed m^3)",
		g.memoryBytes() / 1e6, g.memoryBytes() / 1e3 / ourObserved, g.bytesPerAllocatedVoxel(),
		g.numBlocks(), tree.memoryUsage() / 1e6, tree.memoryUsage() / 1e3 / octoObserved);
	if (a.mrpt) std::printf("; MRPT dense grid %.1f MB (%.0f kB per observed m^3)", mrptBytes / 1e6, mrptBytes / 1e3 / ourObserved);
	std::printf("\n");
}

struct Score
{
	double precision{0}, recall{0}, f1{0};
};
/** Occupied-voxel precision / recall / F1 of `g` against the reference `ref`. */
Score score(const VoxelBlockGrid& g, const VoxelBlockGrid& ref)
{
	std::size_t tp = 0, fp = 0, fn = 0;
	g.forEachKnown([&](const VoxelIndex& v, const Voxel& x) {
		if (x.logOdds <= 0) return;
		const Voxel* r = ref.find(v);
		(r && r->isKnown() && r->logOdds > 0) ? ++tp : ++fp;
	});
	ref.forEachKnown([&](const VoxelIndex& v, const Voxel& x) {
		if (x.logOdds <= 0) return;
		const Voxel* q = g.find(v);
		if (!(q && q->isKnown() && q->logOdds > 0)) ++fn;
	});
	Score s;
	s.precision = tp + fp ? double(tp) / (tp + fp) : 0;
	s.recall = tp + fn ? double(tp) / (tp + fn) : 0;
	s.f1 = s.precision + s.recall > 0 ? 2 * s.precision * s.recall / (s.precision + s.recall) : 0;
	return s;
}

/** Real-data stand-in for the simulator experiment: the frames are integrated at poses with a
 * growing synthetic drift (a), then corrected to ground truth by morphing (b) or by
 * re-integrating the stored depth (c); all are scored against the map built at the
 * ground-truth poses (d). */
void runCorrection(const std::vector<BenchFrame>& frames, const Args& a)
{
	if (frames.size() < 2) return;
	const std::size_t n = frames.size();
	std::vector<CPose3D> drifted(n);
	for (std::size_t i = 0; i < n; ++i)
	{
		// Drift grows linearly to driftM (translation, along (0.75, -0.5, 0.4) / |.|) and
		// driftDeg of yaw (+ a third of it in pitch) at the last frame.
		const double s = double(i) / double(n - 1);
		const double t = a.driftM * s / std::sqrt(0.75 * 0.75 + 0.5 * 0.5 + 0.4 * 0.4);
		const CPose3D D(0.75 * t, -0.5 * t, 0.4 * t, mrpt::DEG2RAD(a.driftDeg * s),
			mrpt::DEG2RAD(a.driftDeg * s / 3.0), 0);
		drifted[i] = D + frames[i].T_world_cam;
	}
	auto build = [&](bool useDrift, bool detectConflicts) {
		CSubmappedOccupancyGrid3D m(a.res);
		if (!detectConflicts) m.insertionOptions.conflict.conflictMinVoxels = 1e12;
		m.insertionOptions.integration.maxRange = a.maxRange;
		m.insertionOptions.integration.minRange = 0.0;
		m.insertionOptions.storeKeyframeDepth = true;
		m.morphingOptions.viewConeMaxRange = a.maxRange;
		if (a.morphWindow >= 0) m.morphingOptions.travelWindow = a.morphWindow;
		if (a.conflictTravel > 0) m.insertionOptions.conflict.travelledDistanceThreshold = a.conflictTravel;
		double travelled = 0;
		for (std::size_t i = 0; i < n; ++i)
		{
			const CPose3D& T = useDrift ? drifted[i] : frames[i].T_world_cam;
			if (i > 0) travelled += T.distanceTo(useDrift ? drifted[i - 1] : frames[i - 1].T_world_cam);
			const auto r = m.insertDepthFrame(frames[i].depth, frames[i].cam, T, travelled, i);
			if (a.verbose && useDrift)
				std::printf("  kf %3zu s=%6.2f m %-12s hits %6zu onOcc %.2f revisit %.2f stale %6zu "
							"staleContra %5zu%s\n",
					i, travelled, toString(r.mode), r.evidence.hits, r.evidence.occupiedHitFraction(),
					r.evidence.revisitHitFraction(), r.evidence.stale,
					r.evidence.staleContradictions, r.conflict ? "  CONFLICT -> new submap" : "");
		}
		return m;
	};
	const CSubmappedOccupancyGrid3D mapA = build(true, true), mapD = build(false, false);
	// False-positive check: the same ground-truth poses with conflict detection on.
	const std::size_t gtSubmaps = build(false, true).numSubmaps();
	TrajectoryCorrection corr;
	for (std::size_t i = 0; i < n; ++i) corr[i] = {drifted[i], frames[i].T_world_cam};
	CSubmappedOccupancyGrid3D mapB = mapA, mapC = mapA, mapBn = mapA;
	// Wall time is what the map reports; process CPU time (all threads) is the work done, which
	// stays comparable when other processes load the machine.
	auto processCpu = [] {
		timespec ts{};
		clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
		return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
	};
	double c0 = processCpu();
	const MorphingStats ms = mapB.morphAndMergeSubmaps(corr);
	const double cpuB = processCpu() - c0;
	// The same morphing with nearest-voxel lookups (the earlier default), for comparison.
	mapBn.morphingOptions.interpolation = MorphingOptions::Interpolation::Nearest;
	c0 = processCpu();
	const MorphingStats msn = mapBn.morphAndMergeSubmaps(corr);
	const double cpuBn = processCpu() - c0;
	c0 = processCpu();
	const auto rs = mapC.reintegrateAtCorrectedPoses(corr);
	const double cpuC = processCpu() - c0;
	const VoxelBlockGrid& ref = mapD.submap(0).grid;
	const Score sa = score(mapA.fusedGrid(), ref), sb = score(mapB.submap(0).grid, ref),
				sc = score(mapC.submap(0).grid, ref), sbn = score(mapBn.submap(0).grid, ref);
	std::printf("\n=== trajectory correction on the same %zu frames (drift up to %.2f m / %.1f deg, "
				"corrected to ground truth) ===\n", n, a.driftM, a.driftDeg);
	std::printf("submaps: %zu in the drifted run, %zu with ground-truth poses (conflict detection on)\n",
		mapA.numSubmaps(), gtSubmaps);
	std::printf("%-40s %9s %9s %9s %10s\n", "occupied voxels vs ground-truth-pose map", "precision", "recall", "F1", "time [ms]");
	std::printf("%-40s %9.3f %9.3f %9.3f %10s\n", "(a) drifted poses, no correction", sa.precision, sa.recall, sa.f1, "-");
	std::printf("%-40s %9.3f %9.3f %9.3f %10.1f\n", "(b) grid morphing + merge", sb.precision, sb.recall, sb.f1, 1000 * ms.seconds);
	std::printf("%-40s %9.3f %9.3f %9.3f %10.1f\n", "(b') morphing, nearest-voxel lookups", sbn.precision, sbn.recall, sbn.f1, 1000 * msn.seconds);
	std::printf("%-40s %9.3f %9.3f %9.3f %10.1f\n", "(c) re-integration of stored depth", sc.precision, sc.recall, sc.f1, 1000 * rs.seconds);
	std::printf("process CPU time [s]: (b) %.3f, (b') %.3f, (c) %.3f -> (c)/(b) %.2f, (c)/(b') %.2f; "
				"%zu corrected voxels evaluated\n",
		cpuB, cpuBn, cpuC, cpuC / std::max(cpuB, 1e-9), cpuC / std::max(cpuBn, 1e-9), ms.evaluatedVoxels);
	std::printf("nearest lookups: F1(b')/F1(c) = %.3f, time(c)/time(b') = %.2f\n", sbn.f1 / std::max(sc.f1, 1e-9),
		rs.seconds / std::max(msn.seconds, 1e-9));
	std::printf("F1(b)/F1(c) = %.4f, time(c)/time(b) = %.2f; morphing: %zu source voxels, %zu morphed, "
				"%zu carried, %zu (block, keyframe) pairs, %zu lookups attempted, %zu averaged\n",
		sb.f1 / std::max(sc.f1, 1e-9), rs.seconds / std::max(ms.seconds, 1e-9), ms.sourceVoxels,
		ms.morphedVoxels, ms.carriedVoxels, ms.blockKeyframePairs, ms.attemptedLookups, ms.lookups);
	// The same morphing (trilinear) with at most K keyframes per corrected block.
	struct KRun
	{
		unsigned k;
		double cpu;
		MorphingStats st;
		VoxelBlockGrid grid;
	};
	std::vector<KRun> kRuns;
	for (const unsigned k : a.morphK)
	{
		CSubmappedOccupancyGrid3D mk = mapA;
		mk.morphingOptions.interpolation = MorphingOptions::Interpolation::Trilinear;
		mk.morphingOptions.maxKeyframesPerBlock = k;
		c0 = processCpu();
		const MorphingStats st = mk.morphAndMergeSubmaps(corr);
		const double cpu = processCpu() - c0;
		const Score sk = score(mk.submap(0).grid, ref);
		std::printf("(b) with morphMaxKeyframesPerBlock %3u: P %.3f R %.3f F1 %.4f -> F1(b)/F1(c) %.4f; "
					"CPU %.3f s -> (c)/(b) %.2f; %zu pairs, %zu attempted, %zu averaged\n",
			k, sk.precision, sk.recall, sk.f1, sk.f1 / std::max(sc.f1, 1e-9), cpu, cpuC / std::max(cpu, 1e-9),
			st.blockKeyframePairs, st.attemptedLookups, st.lookups);
		kRuns.push_back({k, cpu, st, mk.submap(0).grid});
	}
	for (std::size_t s = 0; s < mapA.numSubmaps(); ++s)
		std::printf("  submap %zu: anchor keyframe %llu, %zu keyframes\n", s,
			static_cast<unsigned long long>(mapA.submap(s).anchorKeyframe),
			mapA.submap(s).keyframes.size());
	if (a.gtVoxels.empty()) return;
	// Simulator ground truth: static surface voxels, restricted to the space (d) observed.
	VoxelBlockGrid gt(a.res);
	{
		std::ifstream f(a.gtVoxels);
		std::string line;
		double res = 0;
		std::size_t count = 0;
		while (std::getline(f, line) && count == 0)
		{
			if (line.empty() || line[0] == '#') continue;
			std::istringstream ls(line);
			std::string key;
			ls >> key;
			if (key == "resolution") ls >> res;
			else if (key == "origin")
			{
				double ox = 1, oy = 1, oz = 1;
				ls >> ox >> oy >> oz;
				if (ox != 0 || oy != 0 || oz != 0) throw std::runtime_error("GT origin must be 0");
			}
			else if (key == "count") ls >> count;
		}
		if (std::abs(res - a.res) > 1e-9) throw std::runtime_error("GT resolution differs from --res");
		int i, j, k;
		while (f >> i >> j >> k)
		{
			const Voxel* d = ref.find({i, j, k});
			if (d && d->isKnown()) gt.at({i, j, k}) = Voxel{1.0f, 0.0f};
		}
	}
	const Score ga = score(mapA.fusedGrid(), gt), gb = score(mapB.submap(0).grid, gt),
				gc = score(mapC.submap(0).grid, gt), gd = score(ref, gt), gbn = score(mapBn.submap(0).grid, gt);
	std::printf("occupied voxels vs simulator ground truth (%zu surface voxels observed by (d)):\n",
		gt.numKnownVoxels());
	std::printf("%-40s %9.3f %9.3f %9.3f\n", "(a) drifted poses, no correction", ga.precision, ga.recall, ga.f1);
	std::printf("%-40s %9.3f %9.3f %9.3f\n", "(b) grid morphing + merge", gb.precision, gb.recall, gb.f1);
	std::printf("%-40s %9.3f %9.3f %9.3f\n", "(b') morphing, nearest-voxel lookups", gbn.precision, gbn.recall, gbn.f1);
	std::printf("%-40s %9.3f %9.3f %9.3f\n", "(c) re-integration of stored depth", gc.precision, gc.recall, gc.f1);
	std::printf("%-40s %9.3f %9.3f %9.3f\n", "(d) ground-truth poses", gd.precision, gd.recall, gd.f1);
	std::printf("F1(b)/F1(c) = %.3f (nearest: %.3f), F1(c)/F1(a) = %.3f\n", gb.f1 / std::max(gc.f1, 1e-9),
		gbn.f1 / std::max(gc.f1, 1e-9), gc.f1 / std::max(ga.f1, 1e-9));
	for (const KRun& r : kRuns)
	{
		const Score gk = score(r.grid, gt);
		std::printf("(b) with morphMaxKeyframesPerBlock %3u vs simulator GT: P %.3f R %.3f F1 %.4f -> F1(b)/F1(c) %.4f\n",
			r.k, gk.precision, gk.recall, gk.f1, gk.f1 / std::max(gc.f1, 1e-9));
	}
	// keygrid-slam's own map_3d.bt (its world = its first camera frame): carried into the sim
	// world by the Umeyama alignment of its trajectory to the ground truth, voxel centres mapped
	// to the nearest sim voxel (this resampling alone costs some F1: it is not axis aligned).
	for (const std::string& dir : a.scoreBt)
	{
		octomap::OcTree t(0.1);
		if (!t.readBinary(dir + "/map_3d.bt")) throw std::runtime_error("cannot read " + dir + "/map_3d.bt");
		const auto gtTraj = core::readTumTrajectory(a.simDir + "/groundtruth.txt");
		const auto est = core::readTumTrajectory(dir + "/trajectory.txt");
		std::vector<Eigen::Vector3d> xs, ys;
		std::size_t j = 0;
		for (const auto& e : est)
		{
			while (j < gtTraj.size() && gtTraj[j].t < e.t - 1e-3) ++j;
			if (j < gtTraj.size() && std::abs(gtTraj[j].t - e.t) <= 1e-3)
			{
				xs.emplace_back(e.T_world_cam.x(), e.T_world_cam.y(), e.T_world_cam.z());
				ys.emplace_back(gtTraj[j].T_world_cam.x(), gtTraj[j].T_world_cam.y(), gtTraj[j].T_world_cam.z());
			}
		}
		const auto S = eval::alignPointSets(xs, ys, false);
		VoxelBlockGrid g(a.res);
		const double r = t.getResolution();
		for (auto it = t.begin_leafs(); it != t.end_leafs(); ++it)
		{
			if (!t.isNodeOccupied(*it)) continue;
			const int n = 1 << (16 - int(it.getDepth()));  // voxels per edge of this leaf
			const auto k = it.getIndexKey();  // key of the leaf's first voxel
			for (int dz = 0; dz < n; ++dz)
				for (int dy = 0; dy < n; ++dy)
					for (int dx = 0; dx < n; ++dx)
					{
						const Eigen::Vector3d c((int(k[0]) - 32768 + dx + 0.5) * r, (int(k[1]) - 32768 + dy + 0.5) * r,
							(int(k[2]) - 32768 + dz + 0.5) * r);
						const Eigen::Vector3d w = S.apply(c);
						g.at(g.voxelOf({w.x(), w.y(), w.z()})) = Voxel{1.0f, 0.0f};
					}
		}
		const Score sc = score(g, gt);
		std::printf("%-40s %9.3f %9.3f %9.3f  (%s/map_3d.bt, %zu occupied voxels)\n", "keygrid-slam map_3d.bt", sc.precision,
			sc.recall, sc.f1, dir.c_str(), g.numKnownVoxels());
	}
}

std::vector<BenchFrame> loadTum(const Args& a)
{
	std::vector<BenchFrame> out;
	if (!mrpt::system::directoryExists(a.tum))
	{
		std::printf("TUM folder %s not found: skipped\n", a.tum.c_str());
		return out;
	}
	core::FrameSourceOptions fo;
	if (!a.camera.empty()) fo.camera = core::RgbdCamera::FromPresetOrFile(a.camera);
	core::TumFrameSource src(a.tum, fo);
	const core::Trajectory gt = core::readTumTrajectory(a.tum + "/groundtruth.txt");
	for (unsigned k = 0; k < a.frames; ++k)
	{
		const std::size_t i = std::size_t(k) * a.stride;
		if (i >= src.sequence().pairs().size()) break;
		core::Frame f;
		src.loadFrame(i, f);
		// Ground truth nearest in time (mocap at 100 Hz; every frame has a sample within 5 ms).
		auto it = std::lower_bound(gt.begin(), gt.end(), f.timestamp,
			[](const core::StampedPose& p, double t) { return p.t < t; });
		if (it == gt.end() || (it != gt.begin() && f.timestamp - std::prev(it)->t < it->t - f.timestamp)) --it;
		if (std::abs(it->t - f.timestamp) > 0.02) continue;
		BenchFrame b;
		b.depth = f.depth;
		b.cam = f.camera;
		b.T_world_cam = it->T_world_cam;
		buildCloud(b);
		b.obs = core::makeRgbdObservation(f);
		b.obs->sensorPose = core::sensorPoseFromCameraPose(b.T_world_cam);
		out.push_back(std::move(b));
	}
	return out;
}

std::vector<BenchFrame> loadRawlog(const Args& a)
{
	std::vector<BenchFrame> out;
	if (!mrpt::system::fileExists(a.rawlog)) return out;
	mrpt::obs::CRawlog rawlog;
	if (!rawlog.loadFromRawLogFile(a.rawlog)) return out;
	for (std::size_t i = 0; i < rawlog.size(); ++i)
	{
		mrpt::obs::CObservation3DRangeScan::Ptr o;
		if (rawlog.getType(i) == mrpt::obs::CRawlog::etObservation)
			o = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(rawlog.getAsObservation(i));
		else if (rawlog.getType(i) == mrpt::obs::CRawlog::etSensoryFrame)
			o = rawlog.getAsObservations(i)->getObservationByClass<mrpt::obs::CObservation3DRangeScan>();
		if (!o) continue;
		o->load();
		BenchFrame b;
		b.obs = o;
		b.cam = core::RgbdCamera::FromTCamera(o->cameraParams, o->rangeUnits);
		b.depth.create(int(o->rangeImage.rows()), int(o->rangeImage.cols()), CV_32FC1);
		for (int r = 0; r < b.depth.rows; ++r)
			for (int c = 0; c < b.depth.cols; ++c) b.depth.at<float>(r, c) = o->rangeImage(r, c) * o->rangeUnits;
		b.T_world_cam = core::cameraPoseFromSensorPose(o->sensorPose);
		buildCloud(b);
		out.push_back(std::move(b));
	}
	return out;
}
}  // namespace

int main(int argc, char** argv)
{
	Args a;
	for (int i = 1; i < argc; ++i)
	{
		const std::string k = argv[i];
		auto val = [&]() -> std::string {
			if (i + 1 >= argc) throw std::invalid_argument(k + " needs a value");
			return argv[++i];
		};
		if (k == "--tum") a.tum = val();
		else if (k == "--rawlog") a.rawlog = val();
		else if (k == "--frames") a.frames = unsigned(std::stoul(val()));
		else if (k == "--stride") a.stride = unsigned(std::stoul(val()));
		else if (k == "--repeat") a.repeat = std::max(1u, unsigned(std::stoul(val())));
		else if (k == "--res") a.res = std::stod(val());
		else if (k == "--max-range") a.maxRange = std::stod(val());
		else if (k == "--no-mrpt") a.mrpt = false;
		else if (k == "--morph-window") a.morphWindow = std::stod(val());
		else if (k == "--morph-k")
		{
			std::istringstream ls(val());
			std::string tok;
			while (std::getline(ls, tok, ',')) a.morphK.push_back(unsigned(std::stoul(tok)));
		}
		else if (k == "--conflict-travel") a.conflictTravel = std::stod(val());
		else if (k == "--verbose") a.verbose = true;
		else if (k == "--profile") a.profile = true;
		else if (k == "--score-slam") a.scoreBt.push_back(val());
		else if (k == "--drift") a.driftM = std::stod(val()), a.driftDeg = std::stod(val());
		else if (k == "--sim")
		{
			const std::string d = val();
			a.tum = d + "/tum";
			a.gtVoxels = d + "/occupancy_voxels.txt";
			a.simDir = d;
			a.camera = d + "/tum/camera.ini";
		}
		else
		{
			std::fprintf(stderr, "usage: %s [--tum DIR] [--rawlog FILE] [--frames N] [--stride K] "
				"[--res M] [--max-range M] [--repeat R] [--no-mrpt] [--morph-window M] [--morph-k K1,K2,..] [--conflict-travel M] [--drift M DEG] [--sim DIR] [--verbose] [--profile]\n", argv[0]);
			return k == "--help" ? 0 : 1;
		}
	}
	// The rawlog frame is repeated so its timing averages over several insertions.
	auto raw = loadRawlog(a);
	std::vector<BenchFrame> rawRepeated;
	for (unsigned r = 0; r < 5 && !raw.empty(); ++r) rawRepeated.push_back(raw.front());
	runComparison("tests_rgbd.rawlog (1 real Kinect frame, inserted 5 times)", rawRepeated, a);
	const auto tum = loadTum(a);
	runComparison("TUM " + a.tum, tum, a);
	runCorrection(tum, a);
	return 0;
}
