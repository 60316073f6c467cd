/** CISMOccupancyGrid2D on a synthetic room with a known floor plan: occupied-cell F1 and
 * free-space accuracy from sparse keyframes and from dense depth, in a tilted world (floor from
 * options or from RANSAC), and the rebuild after a trajectory correction. */
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <keygrid/maps/OccupancyGridMetrics.h>

#include <gtest/gtest.h>

#include <random>

#include "ISMSyntheticRoom.h"

using keygrid::CISMOccupancyGrid2D;
using keygrid::maps::evaluateOccupancy;
using keygrid::test::SyntheticRoom;

namespace
{
CISMOccupancyGrid2D::TCreationOptions roomGrid()
{
	CISMOccupancyGrid2D::TCreationOptions c;
	c.min_x = -2.5;
	c.max_x = 2.5;
	c.min_y = -2.5;
	c.max_y = 2.5;
	return c;
}

/** Camera poses: two spots, a full turn each, pitched down 15 degrees, 1 m high. */
std::vector<mrpt::poses::CPose3D> trajectory(const SyntheticRoom& room)
{
	std::vector<mrpt::poses::CPose3D> out;
	for (const auto& [x, y] : {std::pair{-0.8, 0.3}, std::pair{0.9, -0.4}})
		for (int k = 0; k < 12; k++) out.push_back(room.cameraPose(x, y, 1.0, k * M_PI / 6, 15 * M_PI / 180));
	return out;
}

void printMetrics(const keygrid::maps::OccupancyMetrics& m, const char* what)
{
	std::printf(
		"[%s] occupied P=%.3f R=%.3f F1=%.3f (est %zu, gt %zu); free accuracy=%.3f (%zu) free precision=%.3f\n",
		what, m.precision, m.recall, m.f1, m.estOccupied, m.gtOccupied, m.freeAccuracy, m.gtFreeObserved,
		m.freePrecision);
}
}  // namespace

TEST(CISMOccupancyGrid2D_room, SparseKeyframesGiveWallsAndFreeInterior)
{
	SyntheticRoom room;
	for (auto trav : {CISMOccupancyGrid2D::RayTraversal::Bresenham, CISMOccupancyGrid2D::RayTraversal::AntiAliased})
	{
		CISMOccupancyGrid2D grid(roomGrid());
		grid.insertionOptions.rangeNoise = keygrid::maps::RangeNoiseModel::Constant;
		grid.insertionOptions.sigmaConstant = 0.02;
		grid.insertionOptions.rayTraversal = trav;
		std::mt19937 rng(42);
		uint64_t id = 0;
		for (const auto& T : trajectory(room)) grid.insertKeyframePoints(id++, T, room.samplePoints(T, 500, 0.01, rng));
		const auto m = evaluateOccupancy(grid, room.floorPlan());
		printMetrics(m, trav == CISMOccupancyGrid2D::RayTraversal::Bresenham ? "sparse bresenham" : "sparse antialiased");
		EXPECT_GE(m.f1, 0.9);
		EXPECT_GE(m.freeAccuracy, 0.95);
		EXPECT_GE(m.freePrecision, 0.95);
		EXPECT_GT(m.gtFreeObserved, 2000u);
	}
}

TEST(CISMOccupancyGrid2D_room, DenseDepthInTiltedWorldWithConfiguredFloor)
{
	SyntheticRoom room;
	room.T_world_level = mrpt::poses::CPose3D(0.5, -1.0, 0.3, 0.3, 0.2, -0.15);  // TUM-like
	CISMOccupancyGrid2D grid(roomGrid());
	grid.insertionOptions.T_world_floor = room.T_world_level;
	grid.insertionOptions.depthDecimation = 1;
	for (const auto& T_world_cam : trajectory(room))
	{
		// Through the CMetricMap interface: robot pose = MRPT depth-sensor pose, sensorPose = 0.
		const auto obs = room.renderDepth(T_world_cam, 160, 120, 131.25);
		ASSERT_TRUE(grid.insertObservation(obs, keygrid::core::sensorPoseFromCameraPose(T_world_cam)));
	}
	const auto m = evaluateOccupancy(grid, room.floorPlan());
	printMetrics(m, "dense");
	EXPECT_GE(m.f1, 0.9);
	EXPECT_GE(m.freeAccuracy, 0.95);
	EXPECT_EQ(grid.keyframes().size(), 24u);
}

TEST(CISMOccupancyGrid2D_room, FloorFromRansacOnDepth)
{
	SyntheticRoom room;
	room.T_world_level = mrpt::poses::CPose3D(0.5, -1.0, 0.3, 0.3, 0.2, -0.15);
	CISMOccupancyGrid2D grid(roomGrid());
	grid.insertionOptions.estimateFloorFromDepth = true;
	EXPECT_FALSE(grid.floorKnown());
	const auto traj = trajectory(room);
	for (const auto& T : traj) ASSERT_TRUE(grid.insertKeyframeDepth(0, T, room.renderDepth(T, 160, 120, 131.25)));
	ASSERT_TRUE(grid.floorKnown());
	// The estimated floor frame: z axis = the room's up, the first camera 1 m above it.
	const auto T_level_floor = grid.floorPose() - room.T_world_level;
	const auto zAxis = T_level_floor.rotateVector(mrpt::math::TVector3D(0, 0, 1));
	EXPECT_GT(zAxis.z, std::cos(1.0 * M_PI / 180));
	EXPECT_NEAR(T_level_floor.z(), 0.0, 0.01);
	// The estimated floor frame has the first camera's footprint as origin and its heading as
	// x: compare through the (planar) transform between it and the room frame.
	const auto plan = room.floorPlan();
	const auto T_floor_level = room.T_world_level - grid.floorPose();
	const double yaw = T_floor_level.yaw();
	EXPECT_NEAR(T_floor_level.pitch(), 0.0, 0.02);
	EXPECT_NEAR(T_floor_level.roll(), 0.0, 0.02);
	// Free-space accuracy with the room's plan looked up in the estimated floor frame.
	size_t agree = 0, total = 0;
	for (int cy = 0; cy < plan.sizeY; cy++)
		for (int cx = 0; cx < plan.sizeX; cx++)
		{
			const double x = plan.xMin + (cx + 0.5) * plan.resolution, y = plan.yMin + (cy + 0.5) * plan.resolution;
			const double fx = T_floor_level.x() + std::cos(yaw) * x - std::sin(yaw) * y;
			const double fy = T_floor_level.y() + std::sin(yaw) * x + std::cos(yaw) * y;
			const auto s = grid.stateAt(fx, fy);
			const auto g = plan.cell(cx, cy);
			if (g == keygrid::maps::FloorPlanGrid::Free && s != keygrid::CellState::Unknown)
			{
				total++;
				if (s == keygrid::CellState::Free) agree++;
			}
		}
	ASSERT_GT(total, 2000u);
	EXPECT_GE(static_cast<double>(agree) / total, 0.95);
}

TEST(CISMOccupancyGrid2D_room, RebuildAfterTrajectoryCorrectionEqualsFreshMap)
{
	SyntheticRoom room;
	const auto truth = trajectory(room);
	std::mt19937 rng(9);
	std::vector<std::vector<mrpt::math::TPoint3D>> obs;
	for (const auto& T : truth) obs.push_back(room.samplePoints(T, 400, 0.01, rng));

	// Drifted poses: the points are observed relative to the true camera, the map gets a pose
	// that drifts by 2 cm and 1 degree per keyframe.
	CISMOccupancyGrid2D drifted(roomGrid());
	drifted.insertionOptions.rangeNoise = keygrid::maps::RangeNoiseModel::Constant;
	std::map<uint64_t, mrpt::poses::CPose3D> corrected;
	for (size_t k = 0; k < truth.size(); k++)
	{
		const mrpt::poses::CPose3D drift(0.02 * k, 0.0, 0.0, 1.0 * k * M_PI / 180, 0, 0);
		const auto T_drift = drift + truth[k];
		std::vector<mrpt::math::TPoint3D> seen;  // same observation, expressed at the wrong pose
		for (const auto& p : obs[k]) seen.push_back(T_drift.composePoint(truth[k].inverseComposePoint(p)));
		drifted.insertKeyframePoints(k, T_drift, seen);
		corrected[k] = truth[k];
	}
	const double f1Before = evaluateOccupancy(drifted, room.floorPlan()).f1;

	CISMOccupancyGrid2D fresh(roomGrid());
	fresh.insertionOptions = drifted.insertionOptions;
	for (size_t k = 0; k < truth.size(); k++) fresh.insertKeyframePoints(k, truth[k], obs[k]);

	const double seconds = drifted.applyTrajectoryCorrection(corrected);
	EXPECT_GT(seconds, 0.0);
	EXPECT_DOUBLE_EQ(drifted.lastRebuildSeconds(), seconds);
	const double f1After = evaluateOccupancy(drifted, room.floorPlan()).f1;
	std::printf("[rebuild] F1 drifted %.3f -> corrected %.3f, rebuild of %zu keyframes %.3f ms\n", f1Before, f1After,
		truth.size(), 1e3 * seconds);
	EXPECT_LT(f1Before, 0.8);
	EXPECT_GE(f1After, 0.9);
	// Same cells as a map built directly with the corrected poses (float round-off of the
	// camera-frame storage allowed).
	size_t differ = 0;
	for (int cy = 0; cy < fresh.sizeY(); cy++)
		for (int cx = 0; cx < fresh.sizeX(); cx++)
			if (fresh.cellState(cx, cy) != drifted.stateAt(fresh.idx2x(cx), fresh.idx2y(cy)))
				differ++;
	EXPECT_LE(differ, 5u);
	EXPECT_THROW(drifted.applyTrajectoryCorrection({{999, mrpt::poses::CPose3D()}}), std::out_of_range);
}

TEST(CISMOccupancyGrid2D_room, MetricsPenaliseAShiftedFloorPlan)
{
	SyntheticRoom room;
	CISMOccupancyGrid2D grid(roomGrid());
	grid.insertionOptions.rangeNoise = keygrid::maps::RangeNoiseModel::Constant;
	std::mt19937 rng(4);
	uint64_t id = 0;
	for (const auto& T : trajectory(room)) grid.insertKeyframePoints(id++, T, room.samplePoints(T, 500, 0.01, rng));
	auto plan = room.floorPlan();
	EXPECT_GE(evaluateOccupancy(grid, plan).f1, 0.9);
	// The same plan shifted by 4 cells (20 cm) along x: the x-walls no longer match.
	plan.xMin += 0.20;
	const auto shifted = evaluateOccupancy(grid, plan);
	// Only the y-walls (2 x 81 of the 284 wall cells, minus the 4 shifted out) can still match.
	EXPECT_LT(shifted.recall, 0.65);
	EXPECT_LT(shifted.f1, 0.75);
	// ... and a 25 cm tolerance accepts it again.
	keygrid::maps::OccupancyMetricsOptions loose;
	loose.matchTolerance = 0.25;
	EXPECT_GE(evaluateOccupancy(grid, plan, loose).f1, 0.9);
	// The shifted plan calls the real +x wall free: the map's occupied cells there lower the
	// free-space accuracy.
	EXPECT_LT(shifted.freeAccuracy, 1.0);
}
