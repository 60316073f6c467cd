/** CISMOccupancyGrid2D speed: one sparse keyframe (map points), one dense 640x480 depth image,
 * and the rebuild of N keyframes after a trajectory correction. Scene: the synthetic 4 x 3 m
 * room of the unit tests, 5 cm cells. Targets: <= 1 ms sparse, <= 5 ms dense. */
#include <keygrid/maps/CISMOccupancyGrid2D.h>

#include <benchmark/benchmark.h>
#include <octomap/OcTree.h>

#include <random>

#include "ISMSyntheticRoom.h"

using keygrid::CISMOccupancyGrid2D;
using keygrid::test::SyntheticRoom;

namespace
{
std::vector<mrpt::poses::CPose3D> poses(const SyntheticRoom& room, int n)
{
	std::vector<mrpt::poses::CPose3D> out;
	for (int k = 0; k < n; k++)
		out.push_back(room.cameraPose(-0.8 + 1.6 * (k % 7) / 6.0, 0.3 * ((k % 3) - 1), 1.0, k * 2.4, 15 * M_PI / 180));
	return out;
}

CISMOccupancyGrid2D::RayTraversal traversal(int64_t arg)
{
	return arg ? CISMOccupancyGrid2D::RayTraversal::AntiAliased : CISMOccupancyGrid2D::RayTraversal::Bresenham;
}

CISMOccupancyGrid2D::FreeSpaceModel freeSpace(int64_t arg)
{
	return arg ? CISMOccupancyGrid2D::FreeSpaceModel::Paper : CISMOccupancyGrid2D::FreeSpaceModel::HeightBand;
}

/** Args: {points per keyframe, traversal (0 Bresenham, 1 anti-aliased), free space (0 heightBand, 1 paper)} */
void BM_SparseKeyframe(benchmark::State& state)
{
	SyntheticRoom room;
	const auto T = poses(room, 24);
	std::mt19937 rng(1);
	std::vector<std::vector<mrpt::math::TPoint3D>> pts;
	for (const auto& p : T) pts.push_back(room.samplePoints(p, static_cast<size_t>(state.range(0)), 0.01, rng));
	CISMOccupancyGrid2D grid;
	grid.insertionOptions.rangeNoise = keygrid::maps::RangeNoiseModel::Constant;
	grid.insertionOptions.rayTraversal = traversal(state.range(1));
	grid.insertionOptions.freeSpaceModel = freeSpace(state.range(2));
	size_t k = 0;
	for (auto _ : state)
	{
		const size_t i = k++ % T.size();
		grid.insertKeyframePoints(i, T[i], pts[i]);
	}
	state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * state.range(0));
}
BENCHMARK(BM_SparseKeyframe)->ArgsProduct({{100, 500, 2000}, {0, 1}, {0, 1}})->Unit(benchmark::kMicrosecond);

/** Args: {traversal, depth decimation, free space (0 heightBand, 1 paper)} — full 640x480
 * Kinect-like depth image per iteration. */
void BM_DenseDepth640x480(benchmark::State& state)
{
	SyntheticRoom room;
	const auto T = poses(room, 8);
	std::vector<mrpt::obs::CObservation3DRangeScan> obs;
	for (const auto& p : T) obs.push_back(room.renderDepth(p, 640, 480, 525.0));
	CISMOccupancyGrid2D grid;
	grid.insertionOptions.rayTraversal = traversal(state.range(0));
	grid.insertionOptions.depthDecimation = static_cast<int>(state.range(1));
	grid.insertionOptions.freeSpaceModel = freeSpace(state.range(2));
	size_t k = 0;
	for (auto _ : state)
	{
		const size_t i = k++ % T.size();
		grid.insertKeyframeDepth(i, T[i], obs[i]);
	}
	state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * 640 * 480);
}
BENCHMARK(BM_DenseDepth640x480)->ArgsProduct({{0, 1}, {1, 2}, {0, 1}})->Unit(benchmark::kMillisecond);

/** Arg: number of stored keyframes (500 map points each) rebuilt after a correction. */
void BM_RebuildAfterCorrection(benchmark::State& state)
{
	SyntheticRoom room;
	const int n = static_cast<int>(state.range(0));
	const auto T = poses(room, n);
	std::mt19937 rng(2);
	CISMOccupancyGrid2D grid;
	grid.insertionOptions.rangeNoise = keygrid::maps::RangeNoiseModel::Constant;
	std::map<uint64_t, mrpt::poses::CPose3D> corrected;
	for (int k = 0; k < n; k++)
	{
		grid.insertKeyframePoints(static_cast<uint64_t>(k), T[static_cast<size_t>(k)], room.samplePoints(T[static_cast<size_t>(k)], 500, 0.01, rng));
		corrected[static_cast<uint64_t>(k)] = mrpt::poses::CPose3D(0.01, 0, 0, 0.002, 0, 0) + T[static_cast<size_t>(k)];
	}
	for (auto _ : state) benchmark::DoNotOptimize(grid.applyTrajectoryCorrection(corrected));
	state.counters["keyframes"] = n;
}
BENCHMARK(BM_RebuildAfterCorrection)->RangeMultiplier(4)->Range(16, 1024)->Unit(benchmark::kMillisecond);
/** The peers' timed loop: one OctoMap (3D, 5 cm) inserting cloud i (world frame) from the origin of
 * pose T[i], i cycling over the poses, 4.5 m maximum range. */
void insertIntoOctoMap(
	benchmark::State& state, const std::vector<mrpt::poses::CPose3D>& T, const std::vector<octomap::Pointcloud>& clouds)
{
	octomap::OcTree tree(0.05);
	size_t k = 0;
	for (auto _ : state)
	{
		const size_t i = k++ % T.size();
		const auto o = T[i].translation();
		tree.insertPointCloud(clouds[i], octomap::point3d(static_cast<float>(o.x), static_cast<float>(o.y), static_cast<float>(o.z)), 4.5);
	}
}

/** Peer in the same run: OctoMap (3D, 5 cm) inserting the same sparse keyframe points. */
void BM_Peer_OctoMapSparse(benchmark::State& state)
{
	SyntheticRoom room;
	const auto T = poses(room, 24);
	std::mt19937 rng(1);
	std::vector<octomap::Pointcloud> clouds(T.size());
	for (size_t i = 0; i < T.size(); i++)
		for (const auto& p : room.samplePoints(T[i], static_cast<size_t>(state.range(0)), 0.01, rng))
			clouds[i].push_back(static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z));
	insertIntoOctoMap(state, T, clouds);
	state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * state.range(0));
}
BENCHMARK(BM_Peer_OctoMapSparse)->Arg(500)->Unit(benchmark::kMicrosecond);

/** Peer: OctoMap inserting a full 640x480 depth image (every `arg`-th pixel) as a point cloud. */
void BM_Peer_OctoMapDense640x480(benchmark::State& state)
{
	SyntheticRoom room;
	const auto T = poses(room, 4);
	std::vector<octomap::Pointcloud> clouds(T.size());
	for (size_t i = 0; i < T.size(); i++)
		for (const auto& p : keygrid::depthToCameraPoints(room.renderDepth(T[i], 640, 480, 525.0), static_cast<int>(state.range(0))))
		{
			const auto w = T[i].composePoint(mrpt::math::TPoint3D(p.x, p.y, p.z));
			clouds[i].push_back(static_cast<float>(w.x), static_cast<float>(w.y), static_cast<float>(w.z));
		}
	insertIntoOctoMap(state, T, clouds);
}
BENCHMARK(BM_Peer_OctoMapDense640x480)->Arg(1)->Arg(4)->Unit(benchmark::kMillisecond);
}  // namespace

BENCHMARK_MAIN();
