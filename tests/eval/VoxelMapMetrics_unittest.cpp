// VoxelMapMetrics against closed forms: a wall of 20 x 20 true voxels (x = 0.50 .. 0.55 m, 5 cm
// voxels) and maps of it that are exact, shifted, half there, free where the wall is, or seen
// from another world frame that the trajectory alignment undoes.
#include <keygrid/eval/TrajectoryErrors.h>
#include <keygrid/eval/VoxelMapMetrics.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace keygrid;
using eval::VoxelIndex;

namespace
{
constexpr double kRes = 0.05;

/** The wall's voxels with y index in [y0, y1), shifted by dx voxels along x. */
std::vector<VoxelIndex> wall(int dx = 0, int y0 = 0, int y1 = 20)
{
	std::vector<VoxelIndex> v;
	for (int z = 0; z < 20; z++)
		for (int y = y0; y < y1; y++) v.push_back({10 + dx, y, z});
	return v;
}

eval::VoxelTruth truthWall() { return eval::VoxelTruth(kRes, Eigen::Vector3d::Zero(), wall()); }

eval::VoxelMapEstimate mapOf(std::vector<VoxelIndex> occupied, std::vector<VoxelIndex> free = {}, double res = kRes)
{
	eval::VoxelMapEstimate m;
	m.resolution = res;
	m.occupied = std::move(occupied);
	m.free = std::move(free);
	return m;
}
}  // namespace

TEST(VoxelMapMetrics, AMapEqualToTheTruthHasPrecisionAndRecallOne)
{
	const auto m = eval::evaluateVoxelMap(mapOf(wall()), {}, truthWall());
	EXPECT_EQ(m.estOccupied, 400u);
	EXPECT_EQ(m.estOccupiedMatched, 400u);
	EXPECT_DOUBLE_EQ(m.precision, 1.0);
	EXPECT_EQ(m.gtOccupied, 400u);
	EXPECT_DOUBLE_EQ(m.recall, 1.0);
	EXPECT_DOUBLE_EQ(m.seenRecall, 1.0);  // no seen mask: every true voxel counts as seen
	EXPECT_EQ(m.gtSeen, 400u);
	EXPECT_EQ(m.gtCalledFree, 0u);
	EXPECT_EQ(m.hazardVoxels, 0u);
}

TEST(VoxelMapMetrics, TheToleranceDecidesWhetherAShiftedWallMatches)
{
	const auto truth = truthWall();
	// One voxel off: within the default tolerance (one voxel).
	EXPECT_DOUBLE_EQ(eval::evaluateVoxelMap(mapOf(wall(1)), {}, truth).precision, 1.0);
	// Two voxels off: nothing matches with one voxel of tolerance, everything with two.
	const auto two = eval::evaluateVoxelMap(mapOf(wall(2)), {}, truth);
	EXPECT_EQ(two.estOccupiedMatched, 0u);
	EXPECT_DOUBLE_EQ(two.precision, 0.0);
	EXPECT_DOUBLE_EQ(two.recall, 0.0);
	eval::VoxelMapMetricsOptions o;
	o.matchTolerance = 2 * kRes;
	const auto wide = eval::evaluateVoxelMap(mapOf(wall(2)), {}, truth, o);
	EXPECT_DOUBLE_EQ(wide.precision, 1.0);
	EXPECT_DOUBLE_EQ(wide.recall, 1.0);
	// A diagonal neighbour is sqrt(2) voxels away: outside one voxel of tolerance.
	EXPECT_DOUBLE_EQ(eval::evaluateVoxelMap(mapOf({{11, 1, 0}}), {}, truth).precision, 1.0);  // beside (10, 1, 0)
	EXPECT_DOUBLE_EQ(eval::evaluateVoxelMap(mapOf({{11, 20, 0}}), {}, truth).precision, 0.0);  // nearest: (10, 19, 0)
}

TEST(VoxelMapMetrics, AHalfCoveredWallHasRecallOneHalfAndOverTheSeenHalfOne)
{
	auto truth = truthWall();
	const auto half = mapOf(wall(0, 0, 10));
	eval::VoxelMapMetricsOptions exact;
	exact.matchTolerance = 0;
	auto m = eval::evaluateVoxelMap(half, {}, truth, exact);
	EXPECT_DOUBLE_EQ(m.precision, 1.0);
	EXPECT_EQ(m.gtOccupiedMatched, 200u);
	EXPECT_DOUBLE_EQ(m.recall, 0.5);
	// With one voxel of tolerance the next row (y index 10) counts too: 11 of 20 rows.
	EXPECT_DOUBLE_EQ(eval::evaluateVoxelMap(half, {}, truth).recall, 11.0 / 20.0);
	// The cameras saw the map's half (y < 0.5 m) and one more row (y index 10, its voxels beside
	// the map's last row: matched within the tolerance).
	for (int z = 0; z < 20; z++)
		for (int y = 0; y <= 10; y++) EXPECT_EQ(truth.markSeen({0.5, (y + 0.5) * kRes, (z + 0.5) * kRes}), 1);  // on the face x = 0.5
	m = eval::evaluateVoxelMap(half, {}, truth);
	EXPECT_EQ(m.gtSeen, 220u);
	EXPECT_EQ(m.gtSeenMatched, 220u);
	EXPECT_DOUBLE_EQ(m.seenRecall, 1.0);
	EXPECT_DOUBLE_EQ(m.recall, 11.0 / 20.0);
}

TEST(VoxelMapMetrics, APointOnAFaceBetweenTwoTrueVoxelsMarksBoth)
{
	eval::VoxelTruth truth(kRes, Eigen::Vector3d::Zero(), {{10, 0, 0}, {11, 0, 0}, {12, 0, 0}});
	EXPECT_EQ(truth.markSeen({0.55, 0.02, 0.02}), 2);
	EXPECT_EQ(truth.markSeen({0.6249, 0.02, 0.02}), 1);
	EXPECT_EQ(truth.markSeen({3.0, 0.02, 0.02}), 0);
	const auto m = eval::evaluateVoxelMap(mapOf({}), {}, truth);
	EXPECT_EQ(m.gtSeen, 3u);  // (10, 11) by the first point, 12 by the second
}

TEST(VoxelMapMetrics, TrueVoxelsCalledFreeAreHazardsOnlyWithNoMapVoxelNearby)
{
	const auto truth = truthWall();
	// Free space through the whole wall, no obstacle: every true voxel is a hazard.
	auto m = eval::evaluateVoxelMap(mapOf({}, wall()), {}, truth);
	EXPECT_EQ(m.estFree, 400u);
	EXPECT_EQ(m.gtCalledFree, 400u);
	EXPECT_EQ(m.hazardVoxels, 400u);
	// The wall seen one voxel too far, the free space reaching through the true wall: called
	// free, but with the obstacle one voxel away, no hazard.
	m = eval::evaluateVoxelMap(mapOf(wall(1), wall()), {}, truth);
	EXPECT_EQ(m.gtCalledFree, 400u);
	EXPECT_EQ(m.hazardVoxels, 0u);
	// Half the wall missing behind free space: 200 hazards.
	m = eval::evaluateVoxelMap(mapOf(wall(0, 0, 10), wall(0, 10, 20)), {}, truth);
	EXPECT_EQ(m.gtCalledFree, 200u);
	EXPECT_EQ(m.hazardVoxels, 180u);  // the 20 voxels of row y = 10 lie beside the map's wall
}

TEST(VoxelMapMetrics, AMapInAnotherFrameIsCarriedBackByTheTrajectoryAlignment)
{
	// The SLAM world: the ground-truth world turned 90 deg about z and moved by whole voxels,
	// so the map's lattice is the truth's and every voxel has one exact image.
	const mrpt::poses::CPose3D T_map_gt(0.35, -0.20, 0.10, M_PI / 2, 0, 0);
	std::vector<VoxelIndex> inMap;
	for (const auto& v : wall())
	{
		const auto c = T_map_gt.composePoint(mrpt::math::TPoint3D((v[0] + 0.5) * kRes, (v[1] + 0.5) * kRes, (v[2] + 0.5) * kRes));
		inMap.push_back({int(std::floor(c.x / kRes)), int(std::floor(c.y / kRes)), int(std::floor(c.z / kRes))});
	}
	core::Trajectory gt, est;
	for (int i = 0; i < 60; i++)
	{
		const double t = 10 + i / 30.0;
		const mrpt::poses::CPose3D p(std::cos(0.1 * i), std::sin(0.1 * i), 1.2 + 0.05 * std::sin(0.3 * i), 0.1 * i, 0.1, -1.6);
		gt.push_back({t, p});
		est.push_back({t, T_map_gt + p});
	}
	const auto aligned = eval::evaluateTrajectory(gt, est);
	// Without the alignment the map misses the wall; with it, it is the wall.
	EXPECT_DOUBLE_EQ(eval::evaluateVoxelMap(mapOf(inMap), {}, truthWall()).precision, 0.0);
	const auto m = eval::evaluateVoxelMap(mapOf(inMap), aligned.alignment, truthWall());
	EXPECT_DOUBLE_EQ(m.precision, 1.0);
	EXPECT_DOUBLE_EQ(m.recall, 1.0);

	// Up to scale (a monocular map): half-size voxels in a frame half the size, Sim(3) aligned.
	core::Trajectory small;
	for (const auto& p : gt)
	{
		auto q = p.T_world_cam;
		q.x(q.x() * 0.5), q.y(q.y() * 0.5), q.z(q.z() * 0.5);
		small.push_back({p.t, q});
	}
	eval::TrajectoryErrorOptions sim3;
	sim3.withScale = true;
	const auto scaled = eval::evaluateTrajectory(gt, small, sim3);
	EXPECT_NEAR(scaled.alignment.s, 2.0, 1e-9);
	const auto ms = eval::evaluateVoxelMap(mapOf(wall(), {}, kRes / 2), scaled.alignment, eval::VoxelTruth(kRes, {0, 0, 0}, wall()));
	EXPECT_DOUBLE_EQ(ms.precision, 1.0);
	EXPECT_DOUBLE_EQ(ms.recall, 1.0);  // 2.5 cm voxels in a half-size world: the 5 cm wall
}

TEST(VoxelMapMetrics, BadInputIsRefused)
{
	EXPECT_THROW(eval::VoxelTruth(0.0, Eigen::Vector3d::Zero(), {}), std::invalid_argument);
	eval::VoxelMapMetricsOptions o;
	o.matchTolerance = -1;
	EXPECT_FALSE(o.isValid());
	EXPECT_THROW(eval::evaluateVoxelMap(mapOf(wall()), {}, truthWall(), o), std::invalid_argument);
	EXPECT_THROW(eval::evaluateVoxelMap(mapOf(wall(), {}, 0.0), {}, truthWall()), std::invalid_argument);
}
