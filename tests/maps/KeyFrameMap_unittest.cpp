/** maps::KeyFrameMap driven directly, as slam::MetricMaps drives it: a keyframe's map point
 * marks the 2D grid along the closed-form ISM and a correction moves the marks with the
 * keyframe; depth keyframes wait for the run's floor frame and are then taken as they are
 * now; a grid's own floor pose is refused; outputs are tried one by one. */
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <keygrid/maps/InverseSensorModel.h>
#include <keygrid/maps/KeyFrameMap.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <vector>

#include "ISMSyntheticRoom.h"

using keygrid::CellState;
using keygrid::CISMOccupancyGrid2D;
using mrpt::math::TPoint3D;
using mrpt::poses::CPose3D;
namespace maps = keygrid::maps;

namespace
{
/** Camera at (x, y, 0.5) looking along +x; y = 0.025: cell centres on the ray are at r = 0.05 k. */
CPose3D levelCameraAt(double x, double y = 0.025) { return keygrid::test::SyntheticRoom().cameraPose(x, y, 0.5, 0.0, 0.0); }

/** A 2D grid in the paper's free-space model with constant range noise, floor z = 0. */
CISMOccupancyGrid2D paperGrid()
{
	CISMOccupancyGrid2D grid;  // 5 cm, -5..5 m
	grid.insertionOptions.freeSpaceModel = CISMOccupancyGrid2D::FreeSpaceModel::Paper;
	grid.insertionOptions.rangeNoise = maps::RangeNoiseModel::Constant;
	grid.insertionOptions.sigmaConstant = 0.02;
	return grid;
}

/** A 64x48 keyframe facing a flat wall `wallDistance` ahead (depth constant along z). */
maps::MapKeyFrame wallKeyFrame(uint64_t id, const CPose3D& T_world_cam, float wallDistance)
{
	maps::MapKeyFrame kf;
	kf.id = id;
	kf.T_world_cam = T_world_cam;
	kf.camera.width = 64;
	kf.camera.height = 48;
	kf.camera.fx = kf.camera.fy = 50.0;
	kf.camera.cx = 31.5;
	kf.camera.cy = 23.5;
	kf.depth = cv::Mat(48, 64, CV_32F, cv::Scalar(wallDistance));
	return kf;
}
}  // namespace

/* One keyframe with one map point 1 m ahead: every cell on the ray holds the closed-form ISM
 * update logit(practicalIsm(r, 1 m)). Corrected 0.5 m forward, the grid is rebuilt with the
 * point moving with its keyframe: the same profile, 10 cells on. */
TEST(KeyFrameMap, MapPointMarksTheRayAndACorrectionMovesIt)
{
	CISMOccupancyGrid2D grid = paperGrid();
	maps::KeyFrameMap& map = grid;
	map.setFloorFrame(CPose3D());
	const auto shape = grid.insertionOptions.ismShape(grid.resolution());
	const double z = 1.0, sigma = 0.02;
	const int cy = grid.y2idx(0.025), c0 = grid.x2idx(0.025);

	maps::MapKeyFrame kf;
	kf.id = 7;
	kf.T_world_cam = levelCameraAt(0.025);
	kf.points_world = {TPoint3D(0.025 + z, 0.025, 0.5)};
	map.insertKeyFrame(kf, maps::KeyFrameFeed{});
	ASSERT_EQ(grid.keyframes().size(), 1u);

	auto expectProfileFrom = [&](int first) {
		for (int i = 0; i < 30; i++)
		{
			const double r = 0.05 * i;
			double l = maps::logit(maps::practicalIsm(r, z, sigma, shape));
			if (r > z + 0.5 * shape.bandWidth + 8 * sigma) l = 0;  // beyond the traced reach
			EXPECT_NEAR(grid.logOdds(first + i, cy), l, 2e-5) << "cell " << i << " (r = " << r << ")";
		}
	};
	expectProfileFrom(c0);
	EXPECT_EQ(grid.cellState(c0 + 20, cy), CellState::Occupied);
	EXPECT_EQ(grid.cellState(c0 + 10, cy), CellState::Free);

	maps::MapCorrection correction;
	correction.poses[7] = {kf.T_world_cam, levelCameraAt(0.525)};
	correction.poses[99] = {CPose3D(), CPose3D(1, 0, 0, 0, 0, 0)};  // not in this grid: ignored
	EXPECT_TRUE(map.applyCorrection(correction));
	expectProfileFrom(c0 + 10);
	EXPECT_EQ(grid.cellState(c0 + 30, cy), CellState::Occupied);
	EXPECT_EQ(grid.cellState(c0 + 20, cy), CellState::Free);
	EXPECT_EQ(grid.logOdds(c0 + 5, cy), 0.0f);  // behind the corrected camera: never traced
}

/* Depth input before the run's floor frame is known: the keyframe waits; the next keyframe
 * after the floor brings it in, at the pose the run holds then (moved 3 m sideways, as a
 * bundle adjustment might), and each keyframe's wall 2.02 m ahead is in the grid. */
TEST(KeyFrameMap, DepthKeyFramesWaitForTheFloorFrameAndComeBackAsTheyAreNow)
{
	CISMOccupancyGrid2D grid = paperGrid();
	maps::KeyFrameMap& map = grid;
	map.setFloorFrame(std::nullopt);
	EXPECT_FALSE(grid.floorKnown());

	const CPose3D arrived = levelCameraAt(0.025), adjusted = levelCameraAt(0.025, 3.025);
	int lookups = 0;
	maps::KeyFrameFeed feed;
	feed.gridInput = maps::GridInput::Depth;
	feed.keyFrame = [&](uint64_t id) -> std::optional<maps::MapKeyFrame> {
		lookups++;
		EXPECT_EQ(id, 1u);
		return wallKeyFrame(1, adjusted, 2.02f);
	};
	map.insertKeyFrame(wallKeyFrame(1, arrived, 2.02f), feed);
	EXPECT_TRUE(grid.keyframes().empty());

	map.setFloorFrame(CPose3D());  // the floor is z = 0 of the world
	EXPECT_TRUE(grid.keyframes().empty());
	map.insertKeyFrame(wallKeyFrame(2, arrived, 2.02f), feed);
	EXPECT_EQ(lookups, 1);
	ASSERT_EQ(grid.keyframes().size(), 2u);
	EXPECT_EQ(grid.keyframes().at(1).T_world_cam, adjusted);
	// Walls at x = 0.025 + 2.02 = 2.045, in front of each camera: the cells [2.00, 2.05).
	for (double y : {0.025, 3.025})
	{
		EXPECT_EQ(grid.stateAt(2.045, y), CellState::Occupied) << "y = " << y;
		EXPECT_EQ(grid.stateAt(1.025, y), CellState::Free) << "y = " << y;
		EXPECT_EQ(grid.stateAt(2.545, y), CellState::Unknown) << "y = " << y;
	}
}

/* The move of the grid's box under a new floor frame, in closed form: a floor raised by 3 mm
 * moves every point by 3 mm; a floor turned by theta about its z axis moves the box corners
 * (+-5, +-5) most, by the chord 2 sin(theta / 2) |(5, 5)|. */
TEST(KeyFrameMap, FloorFrameShiftIsTheLargestMoveOfTheGridBox)
{
	CISMOccupancyGrid2D grid = paperGrid();  // x, y in [-5, 5] m
	grid.setExternalFloorPose(CPose3D());
	EXPECT_NEAR(grid.floorFrameShift(CPose3D(0, 0, 0.003, 0, 0, 0)), 0.003, 1e-12);
	const double theta = 0.001;
	EXPECT_NEAR(grid.floorFrameShift(CPose3D(0, 0, 0, theta, 0, 0)), 2 * std::sin(theta / 2) * std::sqrt(50.0), 1e-12);
	EXPECT_EQ(grid.floorFrameShift(CPose3D()), 0.0);
}

/* A new floor frame that moves the grid by at most floorReanchorShift keeps the grid as it is
 * (its floor frame and cells); a larger one re-integrates every keyframe in the new frame,
 * cell for cell what a grid built in that frame holds. */
TEST(KeyFrameMap, SmallFloorChangesKeepTheGridLargerOnesRebuildIt)
{
	CISMOccupancyGrid2D grid = paperGrid();
	grid.insertionOptions.floorReanchorShift = 0.01;
	maps::KeyFrameMap& map = grid;
	map.setFloorFrame(CPose3D());
	maps::MapKeyFrame kf;
	kf.id = 1;
	kf.T_world_cam = levelCameraAt(0.025);
	kf.points_world = {TPoint3D(1.025, 0.025, 0.5), TPoint3D(1.025, 0.525, 0.5), TPoint3D(0.525, -0.475, 0.3)};
	map.insertKeyFrame(kf, maps::KeyFrameFeed{});
	const auto cellsOf = [](const CISMOccupancyGrid2D& g) {
		std::vector<float> v;
		for (int cy = 0; cy < g.sizeY(); cy++)
			for (int cx = 0; cx < g.sizeX(); cx++) v.push_back(g.logOdds(cx, cy));
		return v;
	};
	const auto before = cellsOf(grid);

	const CPose3D small(0, 0, 0.008, 0, 0, 0);  // moves the box by 8 mm
	map.setFloorFrame(small);
	EXPECT_EQ(grid.floorPose(), CPose3D());
	EXPECT_EQ(cellsOf(grid), before);

	// 10 cm along x and 5 cm up: every mark moves two cells back.
	const CPose3D large(0.1, 0, 0.05, 0, 0, 0);
	map.setFloorFrame(large);
	EXPECT_EQ(grid.floorPose(), large);
	CISMOccupancyGrid2D fresh = paperGrid();
	maps::KeyFrameMap& freshMap = fresh;
	freshMap.setFloorFrame(large);
	freshMap.insertKeyFrame(kf, maps::KeyFrameFeed{});
	ASSERT_EQ(fresh.sizeX(), grid.sizeX());
	ASSERT_EQ(fresh.sizeY(), grid.sizeY());
	EXPECT_EQ(cellsOf(grid), cellsOf(fresh));
	EXPECT_NE(cellsOf(grid), before);
}

TEST(KeyFrameMap, AGridsOwnFloorPoseIsRefusedNamingTheKey)
{
	CISMOccupancyGrid2D grid;
	grid.insertionOptions.T_world_floor = CPose3D(0, 0, -1, 0, 0, 0);
	maps::KeyFrameMap& map = grid;
	try
	{
		map.setFloorFrame(std::nullopt);
		FAIL() << "a grid's own T_world_floor must not be replaced silently";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("_insertOpts] T_world_floor"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find("[floor] T_world_floor"), std::string::npos) << e.what();
	}
}

/* Every file is tried: with the folder missing, each of the 3D grid's three files fails and
 * the first failure is thrown naming how many more there were. */
TEST(KeyFrameMap, OutputsAreTriedOneByOne)
{
	keygrid::CSubmappedOccupancyGrid3D grid;
	const maps::KeyFrameMap& map = grid;
	const auto dir = std::filesystem::temp_directory_path() / "keygrid_keyframemap_outputs";
	std::filesystem::remove_all(dir);
	std::filesystem::create_directories(dir);

	maps::MapOutputFolder good(dir.string(), {});
	map.writeOutputs(good, "_1");
	EXPECT_EQ(good.files(), (std::vector<std::string>{"map_3d_1.bt", "map_3d_1.ply", "map_3d_1.bin"}));
	EXPECT_NO_THROW(good.throwIfAnyFailed());
	for (const auto& f : good.files()) EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;

	maps::MapOutputFolder missing((dir / "missing").string(), {});
	map.writeOutputs(missing, "");
	EXPECT_TRUE(missing.files().empty());
	try
	{
		missing.throwIfAnyFailed();
		FAIL() << "failures must be reported";
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_NE(std::string(e.what()).find("(and 2 more map files not written)"), std::string::npos) << e.what();
	}
	std::filesystem::remove_all(dir);
}

/* A monocular map given metric scale: a correction with scale 2 names no pose, and the grid
 * scales what it stored, the keyframe stored before the floor frame was known included. The
 * camera at (0.0375, 0.0375, 0.5) with its map point 1 m ahead becomes a camera at (0.075,
 * 0.075, 1) with its point 2 m ahead, on a row of cell centres: the point's cell (x = 2.075) is
 * occupied, the cell of the unscaled point (x = 1.0375) is on the free part of the new ray, and
 * nothing short of the band is occupied. The 3D grid, built from depth, refuses a scale. */
TEST(KeyFrameMap, AScaleCorrectionScalesTheStoredRaysAndTheirPoses)
{
	CISMOccupancyGrid2D grid = paperGrid();
	maps::KeyFrameMap& map = grid;
	map.setFloorFrame(std::nullopt);  // the run's floor frame is not known yet
	maps::MapKeyFrame kf;
	kf.id = 3;
	kf.T_world_cam = levelCameraAt(0.0375, 0.0375);
	kf.points_world = {TPoint3D(1.0375, 0.0375, 0.5)};
	map.insertKeyFrame(kf, maps::KeyFrameFeed{});
	EXPECT_EQ(grid.countStates()[2], 0u);  // stored only

	maps::MapCorrection correction;
	correction.scale = 2.0;
	correction.T_world_floor = CPose3D();
	EXPECT_TRUE(map.applyCorrection(correction));
	EXPECT_NEAR(grid.keyframes().at(3).T_world_cam.z(), 1.0, 1e-12);
	EXPECT_EQ(grid.stateAt(2.075, 0.075), CellState::Occupied);
	EXPECT_EQ(grid.stateAt(1.0375, 0.075), CellState::Free);
	for (double x = 0.1; x < 1.9; x += 0.05) EXPECT_NE(grid.stateAt(x, 0.075), CellState::Occupied) << "x = " << x;

	correction.scale = 0.0;
	EXPECT_THROW(map.applyCorrection(correction), std::invalid_argument);

	keygrid::CSubmappedOccupancyGrid3D grid3d;
	maps::KeyFrameMap& map3d = grid3d;
	correction.scale = 2.0;
	EXPECT_FALSE(map3d.applyCorrection(correction));  // nothing to rescale
	map3d.insertKeyFrame(wallKeyFrame(1, levelCameraAt(0.0), 2.0f), maps::KeyFrameFeed{});
	EXPECT_THROW(map3d.applyCorrection(correction), std::invalid_argument);
}
