/** CISMOccupancyGrid2D's height-aware free space (freeSpaceModel = heightBand) against the
 * paper's 2D free space on the two scenes that break the latter: a table whose top is seen but
 * under which no ray reaches the floor, and a low box in front of a wall that the camera later
 * looks over. Rendered by ray casting (ISMSyntheticRoom.h), so the truth is the boxes. */
#include <keygrid/maps/CISMOccupancyGrid2D.h>

#include <gtest/gtest.h>

#include "ISMSyntheticRoom.h"

using keygrid::CellState;
using keygrid::CISMOccupancyGrid2D;
using keygrid::test::SyntheticRoom;
using Model = CISMOccupancyGrid2D::FreeSpaceModel;

namespace
{
constexpr int kW = 160, kH = 120;
constexpr double kF = 131.25;  // 62.7 x 49.1 degree field of view

CISMOccupancyGrid2D makeGrid(Model model)
{
	CISMOccupancyGrid2D::TCreationOptions c;
	c.min_x = -2.5;
	c.max_x = 2.5;
	c.min_y = -2.5;
	c.max_y = 2.5;
	CISMOccupancyGrid2D grid(c);
	grid.insertionOptions.freeSpaceModel = model;
	grid.insertionOptions.rangeNoise = keygrid::maps::RangeNoiseModel::Constant;
	grid.insertionOptions.sigmaConstant = 0.01;
	grid.insertionOptions.depthDecimation = 1;  // the images are 160 x 120
	return grid;
}

/** Cells whose centre lies inside a box's footprint, shrunk by `margin` [m]. */
std::vector<std::pair<int, int>> footprintCells(const CISMOccupancyGrid2D& g, const SyntheticRoom::Box& b, double margin)
{
	std::vector<std::pair<int, int>> out;
	for (int cy = 0; cy < g.sizeY(); cy++)
		for (int cx = 0; cx < g.sizeX(); cx++)
		{
			const double x = g.idx2x(cx), y = g.idx2y(cy);
			if (x > b.lo.x + margin && x < b.hi.x - margin && y > b.lo.y + margin && y < b.hi.y - margin)
				out.emplace_back(cx, cy);
		}
	return out;
}

size_t countState(const CISMOccupancyGrid2D& g, const std::vector<std::pair<int, int>>& cells, CellState s)
{
	size_t n = 0;
	for (const auto& [cx, cy] : cells) n += g.cellState(cx, cy) == s;
	return n;
}

/** Depth pixels landing on the floor (z < 2 cm) inside a footprint: the scene's precondition. */
size_t floorHitsUnder(
	const mrpt::poses::CPose3D& T_world_cam, const mrpt::obs::CObservation3DRangeScan& obs, const SyntheticRoom::Box& b)
{
	size_t n = 0;
	for (const auto& p : keygrid::depthToCameraPoints(obs, 1))
	{
		const auto w = T_world_cam.composePoint(mrpt::math::TPoint3D(p.x, p.y, p.z));
		n += w.z < 0.02 && b.containsXY(w.x, w.y);
	}
	return n;
}
}  // namespace

/* A 0.8 x 0.6 m table, top 0.70-0.75 m on four legs, seen from twelve cameras around it at
 * eye height 1 m looking level, then from eight cameras standing at its edges: the top is in view,
 * the floor under it never is (checked). From the edges the near part of the top is below the
 * field of view while the rays to the walls pass over it. */
TEST(CISMOccupancyGrid2D_band, TableStaysOccupiedFromEveryViewpoint)
{
	SyntheticRoom room;
	const SyntheticRoom::Box top{{-0.4, -0.3, 0.70}, {0.4, 0.3, 0.75}};
	room.boxes.push_back(top);
	for (double sx : {-1.0, 1.0})
		for (double sy : {-1.0, 1.0})
		{
			const double x = sx > 0 ? 0.36 : -0.4, y = sy > 0 ? 0.26 : -0.3;
			room.boxes.push_back({{x, y, 0.0}, {x + 0.04, y + 0.04, 0.70}});
		}
	std::vector<mrpt::poses::CPose3D> cams;
	for (int k = 0; k < 12; k++)
	{
		const double a = k * M_PI / 6;
		cams.push_back(room.cameraPose(-1.2 * std::cos(a), -1.2 * std::sin(a), 1.0, a, 0.0));
	}
	for (int k = 0; k < 8; k++)
	{
		const double a = k * M_PI / 4;
		cams.push_back(room.cameraPose(-0.6 * std::cos(a), -0.6 * std::sin(a), 1.0, a, 0.0));
	}
	for (Model model : {Model::HeightBand, Model::Paper})
	{
		auto grid = makeGrid(model);
		const auto cells = footprintCells(grid, top, 0.03);
		ASSERT_GT(cells.size(), 120u);
		size_t maxFree = 0;
		uint64_t id = 0;
		for (const auto& T : cams)
		{
			const auto obs = room.renderDepth(T, kW, kH, kF);
			ASSERT_EQ(floorHitsUnder(T, obs, top), 0u) << "scene: a ray reached the floor under the table";
			ASSERT_TRUE(grid.insertKeyframeDepth(id++, T, obs));
			maxFree = std::max(maxFree, countState(grid, cells, CellState::Free));
			if (model == Model::HeightBand)
			{
				ASSERT_EQ(countState(grid, cells, CellState::Free), 0u) << "table called free after keyframe " << id;
			}
		}
		const size_t occupied = countState(grid, cells, CellState::Occupied);
		std::printf("[%s] table: %zu cells, %zu occupied at the end, at most %zu free on the way\n",
			model == Model::HeightBand ? "heightBand" : "paper", cells.size(), occupied, maxFree);
		if (model == Model::HeightBand)
		{
			EXPECT_EQ(occupied, cells.size());
		}
	}
}

/* A 0.3 m high crate 2.5 cm in front of a wall. Three keyframes from 3 m away see it; then the
 * camera walks up and looks level at the wall, the crate below its field of view, so the rays to
 * the wall pass over the crate: the paper's model frees the crate, the height band must not.
 * The floor between the camera and the crate must still come out free. */
TEST(CISMOccupancyGrid2D_band, LowBoxInFrontOfAWallIsNeverCalledFree)
{
	SyntheticRoom room;
	const SyntheticRoom::Box crate{{1.6, -0.3, 0.0}, {2.0, 0.3, 0.3}};
	room.boxes.push_back(crate);
	std::vector<mrpt::poses::CPose3D> far, near;
	for (double y : {-0.3, 0.0, 0.3}) far.push_back(room.cameraPose(-1.0, y, 1.0, 0.0, 15 * M_PI / 180));
	for (int k = 0; k < 10; k++) near.push_back(room.cameraPose(0.9, -0.25 + 0.05 * k, 1.0, 0.0, 0.0));
	for (Model model : {Model::HeightBand, Model::Paper})
	{
		auto grid = makeGrid(model);
		const auto cells = footprintCells(grid, crate, 0.03);
		uint64_t id = 0;
		for (const auto& T : far) ASSERT_TRUE(grid.insertKeyframeDepth(id++, T, room.renderDepth(T, kW, kH, kF)));
		const size_t seen = countState(grid, cells, CellState::Occupied);
		ASSERT_GE(seen, 40u) << "the far keyframes must see the crate";
		for (const auto& T : near)
		{
			const auto obs = room.renderDepth(T, kW, kH, kF);
			for (const auto& p : keygrid::depthToCameraPoints(obs, 1))
			{
				const auto w = T.composePoint(mrpt::math::TPoint3D(p.x, p.y, p.z));
				ASSERT_FALSE(crate.containsXY(w.x, w.y) && w.z < 0.31) << "scene: the near keyframes must not see the crate";
			}
			ASSERT_TRUE(grid.insertKeyframeDepth(id++, T, obs));
			if (model == Model::HeightBand)
			{
				ASSERT_EQ(countState(grid, cells, CellState::Free), 0u) << "crate called free after keyframe " << id;
			}
		}
		const size_t freeAtEnd = countState(grid, cells, CellState::Free);
		std::printf("[%s] crate: %zu cells, %zu occupied after the far views, %zu free at the end\n",
			model == Model::HeightBand ? "heightBand" : "paper", cells.size(), seen, freeAtEnd);
		// The floor in front of the crate, seen by the far keyframes.
		size_t floorFree = 0, floorCells = 0;
		for (double x = 0.325; x < 1.4; x += 0.05)
			for (double y = -0.2; y <= 0.2; y += 0.05)
			{
				floorCells++;
				floorFree += grid.stateAt(x, y) == CellState::Free;
			}
		if (model == Model::HeightBand)
		{
			EXPECT_EQ(countState(grid, cells, CellState::Occupied), seen);
			EXPECT_GE(floorFree, floorCells * 95 / 100) << floorFree << " of " << floorCells;
		}
		else
			EXPECT_GT(freeAtEnd, seen / 2) << "the paper's model no longer frees a box the camera looks over";
	}
}

/* Rays that pass above a known obstacle leave it, rays through its height clear it: a crate
 * removed from the scene becomes free once the camera sees the floor where it stood. */
TEST(CISMOccupancyGrid2D_band, RemovedObstacleIsClearedByRaysThroughIt)
{
	SyntheticRoom room;
	const SyntheticRoom::Box crate{{0.2, -0.3, 0.0}, {0.6, 0.3, 0.3}};
	room.boxes.push_back(crate);
	auto grid = makeGrid(Model::HeightBand);
	const auto cells = footprintCells(grid, crate, 0.03);
	uint64_t id = 0;
	std::vector<mrpt::poses::CPose3D> cams;
	for (double y : {-0.3, 0.0, 0.3}) cams.push_back(room.cameraPose(-1.0, y, 1.0, 0.0, 25 * M_PI / 180));
	for (const auto& T : cams) grid.insertKeyframeDepth(id++, T, room.renderDepth(T, kW, kH, kF));
	EXPECT_EQ(countState(grid, cells, CellState::Occupied), cells.size());
	room.boxes.clear();
	for (int rep = 0; rep < 3; rep++)
		for (const auto& T : cams) grid.insertKeyframeDepth(id++, T, room.renderDepth(T, kW, kH, kF));
	EXPECT_EQ(countState(grid, cells, CellState::Free), cells.size());
}

/* One floor point 2 m ahead of a camera at 1.4 m: its ray is under obstacleMinHeight (0.10 m)
 * over its last 2 * 0.10 / 1.4 = 0.143 m, so the floor is seen, and cleared, in the cells from
 * x = 1.857 m to the point (a cell is cleared when its centre is within the ray's reach).
 * floorRayMargin = 0.08 m ends the ray at x = 1.92 m: the cells centred at 1.975 and 1.925 m
 * stay unknown, the one at 1.875 m is still cleared. */
TEST(CISMOccupancyGrid2D_band, FloorRayMarginKeepsTheCellsAtAFloorPointUncleared)
{
	SyntheticRoom room;
	const auto T = room.cameraPose(0.0, 0.025, 1.4, 0.0, 35 * M_PI / 180);
	const std::vector<mrpt::math::TPoint3D> floorPoint{{2.0, 0.025, 0.0}};
	for (const double margin : {0.0, 0.08})
	{
		SCOPED_TRACE(margin);
		auto grid = makeGrid(Model::HeightBand);
		grid.insertionOptions.floorRayMargin = margin;
		for (uint64_t id = 0; id < 2; id++) ASSERT_TRUE(grid.insertKeyframePoints(id, T, floorPoint));
		EXPECT_EQ(grid.stateAt(1.975, 0.025), margin > 0 ? CellState::Unknown : CellState::Free);
		EXPECT_EQ(grid.stateAt(1.925, 0.025), margin > 0 ? CellState::Unknown : CellState::Free);
		EXPECT_EQ(grid.stateAt(1.875, 0.025), CellState::Free);
		EXPECT_EQ(grid.stateAt(1.775, 0.025), CellState::Unknown);  // the ray is 0.16 m high there
	}
}
