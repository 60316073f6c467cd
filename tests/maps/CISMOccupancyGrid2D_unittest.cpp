/** CISMOccupancyGrid2D: log-odds update along a ray against the closed-form ISM, clamping,
 * options, and creation from an INI through CMultiMetricMap. */
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/system/filesystem.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "ISMSyntheticRoom.h"
#include "MapIniChecks.h"
#include "TestData.h"

using keygrid::CellState;
using keygrid::CISMOccupancyGrid2D;
using mrpt::math::TPoint3D;

namespace
{
/** Camera at (0.025, 0.025, 0.5) looking along +x: cell centres on the ray are at r = 0.05 k. */
mrpt::poses::CPose3D levelCamera() { return keygrid::test::SyntheticRoom().cameraPose(0.025, 0.025, 0.5, 0.0, 0.0); }
}  // namespace

/* A level ray at 0.5 m to an obstacle 1 m ahead. Paper model: each cell on it follows the
 * closed-form ISM update. Height band: the ray stays in one height slice, which follows the same
 * update; the column shows it where it is positive (obstacle evidence) and is unknown elsewhere,
 * since the ray never came below obstacleMinHeight to see the ground clear. */
TEST(CISMOccupancyGrid2D, LogOddsUpdateFollowsClosedFormIsmAndClamps)
{
	using Model = CISMOccupancyGrid2D::FreeSpaceModel;
	for (auto model : {Model::Paper, Model::HeightBand})
	for (auto trav : {CISMOccupancyGrid2D::RayTraversal::Bresenham, CISMOccupancyGrid2D::RayTraversal::AntiAliased})
	{
		CISMOccupancyGrid2D grid;  // 5 cm, -5..5 m
		auto& o = grid.insertionOptions;
		o.freeSpaceModel = model;
		o.rangeNoise = keygrid::maps::RangeNoiseModel::Constant;
		o.sigmaConstant = 0.02;
		o.rayTraversal = trav;
		const auto shape = o.ismShape(grid.resolution());
		const double z = 1.0;
		const std::vector<TPoint3D> pts{TPoint3D(0.025 + z, 0.025, 0.5)};
		const int cy = grid.y2idx(0.025);
		const int c0 = grid.x2idx(0.025);
		ASSERT_EQ(c0, 100);

		std::vector<double> expected(40, 0.0);
		for (int k = 1; k <= 12; k++)
		{
			ASSERT_TRUE(grid.insertKeyframePoints(static_cast<uint64_t>(k), levelCamera(), pts));
			for (int i = 0; i < 40; i++)
			{
				const double r = 0.05 * i;
				double inc = keygrid::maps::logit(keygrid::maps::practicalIsm(r, z, 0.02, shape));
				if (r > z + 0.5 * shape.bandWidth + 8 * 0.02) inc = 0;  // beyond the traced reach
				expected[static_cast<size_t>(i)] = std::clamp(expected[static_cast<size_t>(i)] + inc, o.logOddsMin, o.logOddsMax);
				const double column = model == Model::Paper ? expected[static_cast<size_t>(i)] : std::max(0.0, expected[static_cast<size_t>(i)]);
				ASSERT_NEAR(grid.logOdds(c0 + i, cy), column, 2e-5)
					<< "insertion " << k << " cell " << i << " (r=" << r << ")";
			}
		}
		// Saturated: the endpoint cell at the clamp maximum, cells before it at the minimum.
		EXPECT_NEAR(grid.logOdds(c0 + 20, cy), o.logOddsMax, 1e-6);
		EXPECT_NEAR(grid.logOdds(c0 + 10, cy), model == Model::Paper ? o.logOddsMin : 0.0, 1e-6);
		EXPECT_EQ(grid.cellState(c0 + 20, cy), CellState::Occupied);
		EXPECT_EQ(grid.cellState(c0 + 10, cy), model == Model::Paper ? CellState::Free : CellState::Unknown);
		EXPECT_EQ(grid.cellState(c0 + 30, cy), CellState::Unknown);
		// Cells off the ray are untouched.
		EXPECT_EQ(grid.logOdds(c0 + 10, cy + 3), 0.0f);
		EXPECT_EQ(grid.keyframes().size(), 12u);
	}
}

TEST(CISMOccupancyGrid2D, HeightBandSelectsObstacles)
{
	CISMOccupancyGrid2D grid;
	const int cy = grid.y2idx(0.025);
	// Below the band (but above the floor tolerance) and above it: ignored entirely.
	grid.insertKeyframePoints(1, levelCamera(), {TPoint3D(1.025, 0.025, 0.07), TPoint3D(1.025, 0.025, 2.2)});
	EXPECT_TRUE(grid.isEmpty());
	// Non-finite points are dropped.
	const double nan = std::numeric_limits<double>::quiet_NaN();
	grid.insertKeyframePoints(9, levelCamera(), {TPoint3D(nan, 0.025, 1.0), TPoint3D(1.0, nan, 1.0)});
	EXPECT_TRUE(grid.isEmpty());
	// A floor point only clears, nothing occupied; height band (the default): only the cells
	// where the ray from the camera at 0.5 m is below obstacleMinHeight = 0.1 m (the last 0.2 m).
	grid.insertKeyframePoints(2, levelCamera(), {TPoint3D(1.025, 0.025, 0.0)});
	EXPECT_EQ(grid.cellState(grid.x2idx(0.5), cy), CellState::Unknown);
	EXPECT_EQ(grid.cellState(grid.x2idx(0.725), cy), CellState::Unknown);
	EXPECT_EQ(grid.cellState(grid.x2idx(0.875), cy), CellState::Free);
	EXPECT_EQ(grid.cellState(grid.x2idx(1.025), cy), CellState::Free);
	EXPECT_EQ(grid.countStates()[2], 0u);
	// The paper's model frees the whole ray.
	CISMOccupancyGrid2D paper;
	paper.insertionOptions.freeSpaceModel = CISMOccupancyGrid2D::FreeSpaceModel::Paper;
	paper.insertKeyframePoints(2, levelCamera(), {TPoint3D(1.025, 0.025, 0.0)});
	EXPECT_EQ(paper.cellState(paper.x2idx(0.5), cy), CellState::Free);
	// An obstacle in the band is occupied.
	grid.insertKeyframePoints(3, levelCamera(), {TPoint3D(1.025, 0.025, 1.2)});
	EXPECT_EQ(grid.cellState(grid.x2idx(1.025), cy), CellState::Occupied);
}

/* heightBand with the most slices allowed (64): an obstacle in the last slice (0.8875-0.90 m),
 * then rays to a lower point further on that cross its cell's column in that slice, coming from
 * a camera above the band: they clear it. The column then reads unknown, not free: no ray saw
 * its ground clearance. */
TEST(CISMOccupancyGrid2D, RaysThroughTheBandsTopSliceClearIt)
{
	CISMOccupancyGrid2D grid;
	auto& o = grid.insertionOptions;
	o.obstacleMinHeight = 0.1;
	o.obstacleMaxHeight = 0.9;
	o.bandSliceHeight = (o.obstacleMaxHeight - o.obstacleMinHeight) / 64;
	const auto camera = keygrid::test::SyntheticRoom().cameraPose(0.025, 0.025, 0.95, 0.0, 0.0);
	const int cx = grid.x2idx(1.025), cy = grid.y2idx(0.025);
	grid.insertKeyframePoints(1, camera, {TPoint3D(1.025, 0.025, 0.895)});
	ASSERT_EQ(grid.cellState(cx, cy), CellState::Occupied);
	// From (0.025, 0.95) to (3.025, 0.785): 0.8964-0.8936 m over the column at x = 1.0-1.05.
	uint64_t id = 2;
	while (grid.cellState(cx, cy) == CellState::Occupied && id < 40)
		grid.insertKeyframePoints(id++, camera, {TPoint3D(3.025, 0.025, 0.785)});
	EXPECT_EQ(grid.cellState(cx, cy), CellState::Unknown);
	EXPECT_LE(id, 12u);
}

TEST(CISMOccupancyGrid2D, GrowsToContainFarPoints)
{
	CISMOccupancyGrid2D::TCreationOptions c;
	c.min_x = c.min_y = -1;
	c.max_x = c.max_y = 1;
	CISMOccupancyGrid2D grid(c);
	grid.insertKeyframePoints(1, levelCamera(), {TPoint3D(3.025, 0.025, 1.0)});
	EXPECT_GE(grid.xMax(), 3.2);
	EXPECT_DOUBLE_EQ(grid.xMin(), -1.0);
	EXPECT_EQ(grid.stateAt(3.025, 0.025), CellState::Occupied);
	// Cells keep their lattice: the cell centre at 3.025 is still a centre.
	EXPECT_NEAR(grid.idx2x(grid.x2idx(3.025)), 3.025, 1e-9);
}

TEST(CISMOccupancyGrid2D, OptionsSaveLoadRoundTripAndErrorsNameTheKey)
{
	CISMOccupancyGrid2D::TInsertionOptions a;
	a.pOccupied = 0.8;
	a.bandWidth = 0.1;
	a.rangeNoise = keygrid::maps::RangeNoiseModel::Constant;
	a.rayTraversal = CISMOccupancyGrid2D::RayTraversal::AntiAliased;
	a.T_world_floor = mrpt::poses::CPose3D(1, 2, 3, 0.1, 0.2, 0.3);
	a.floorRansac.iterations = 77;
	a.floorUpHint = mrpt::math::TVector3D(0, 0.5, 1.0 / 3.0);  // 1/3 is written exactly too
	a.estimateFloorFromDepth = true;
	a.freeSpaceModel = CISMOccupancyGrid2D::FreeSpaceModel::Paper;
	mrpt::config::CConfigFileMemory saved;
	a.saveToConfigFile(saved, "ins");
	// Through the INI text: the written lines are padded and carry their description.
	const mrpt::config::CConfigFileMemory cfg(saved.getContent());
	CISMOccupancyGrid2D::TInsertionOptions b;
	b.loadFromConfigFile(cfg, "ins");
	EXPECT_DOUBLE_EQ(b.pOccupied, 0.8);
	EXPECT_DOUBLE_EQ(b.bandWidth, 0.1);
	EXPECT_EQ(b.rangeNoise, keygrid::maps::RangeNoiseModel::Constant);
	EXPECT_EQ(b.rayTraversal, CISMOccupancyGrid2D::RayTraversal::AntiAliased);
	EXPECT_EQ(b.floorRansac.iterations, 77);
	EXPECT_NEAR((b.T_world_floor - a.T_world_floor).translation().norm(), 0.0, 1e-6);
	// TVector3D is a packed struct: copy its fields before gtest binds them to references.
	const double upY = b.floorUpHint.y, upZ = b.floorUpHint.z;
	EXPECT_EQ(upY, 0.5);
	EXPECT_EQ(upZ, 1.0 / 3.0);
	EXPECT_TRUE(b.estimateFloorFromDepth);
	EXPECT_EQ(b.freeSpaceModel, CISMOccupancyGrid2D::FreeSpaceModel::Paper);

	mrpt::config::CConfigFileMemory bad;
	bad.write("ins", "rayTraversal", "zigzag");
	try
	{
		b.loadFromConfigFile(bad, "ins");
		FAIL() << "expected an exception";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("rayTraversal"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find("zigzag"), std::string::npos) << e.what();
	}
	mrpt::config::CConfigFileMemory bad2;
	bad2.write("c", "resolution", -0.1);
	CISMOccupancyGrid2D::TCreationOptions c;
	EXPECT_THROW(c.loadFromConfigFile(bad2, "c"), std::invalid_argument);
}

TEST(CISMOccupancyGrid2D, CreatedFromIniThroughCMultiMetricMap)
{
	const std::string ini = R"(
[map]
ismOccupancyGrid2D_count = 1
pointsMap_count = 1

[map_ismOccupancyGrid2D_00_creationOpts]
resolution = 0.10
min_x = -3
max_x = 4
min_y = -2
max_y = 2

[map_ismOccupancyGrid2D_00_insertOpts]
pOccupied = 0.8
rangeNoise = constant
sigmaConstant = 0.03
rayTraversal = antialiased
obstacleMaxHeight = 1.5

[map_ismOccupancyGrid2D_00_likelihoodOpts]
decimation = 4
)";
	mrpt::config::CConfigFileMemory cfg(ini);
	mrpt::maps::TSetOfMetricMapInitializers inits;
	inits.loadFromConfigFile(cfg, "map");
	ASSERT_EQ(inits.size(), 2u);
	mrpt::maps::CMultiMetricMap mm;
	mm.setListOfMaps(inits);
	const auto grid = mm.mapByClass<CISMOccupancyGrid2D>();
	ASSERT_TRUE(grid) << "the INI asked for an ismOccupancyGrid2D but none was created";
	EXPECT_DOUBLE_EQ(grid->resolution(), 0.10);
	EXPECT_DOUBLE_EQ(grid->xMin(), -3.0);
	EXPECT_EQ(grid->sizeX(), 70);
	EXPECT_EQ(grid->sizeY(), 40);
	EXPECT_DOUBLE_EQ(grid->insertionOptions.pOccupied, 0.8);
	EXPECT_DOUBLE_EQ(grid->insertionOptions.sigmaConstant, 0.03);
	EXPECT_EQ(grid->insertionOptions.rayTraversal, CISMOccupancyGrid2D::RayTraversal::AntiAliased);
	EXPECT_DOUBLE_EQ(grid->insertionOptions.obstacleMaxHeight, 1.5);
	EXPECT_EQ(grid->likelihoodOptions.decimation, 4);

	// The multi-map forwards a depth observation to the grid.
	keygrid::test::SyntheticRoom room;
	const auto T_world_cam = room.cameraPose(0, 0, 1.0, 0.3, 0.2);
	auto obs = room.renderDepth(T_world_cam, 80, 60, 65.0);
	EXPECT_TRUE(mm.insertObservation(obs, keygrid::core::sensorPoseFromCameraPose(T_world_cam)));
	EXPECT_GT(grid->countStates()[2], 5u);
	EXPECT_TRUE(grid->canComputeObservationLikelihood(obs));
	// The true pose explains the image better than a shifted one.
	const auto T_robot = keygrid::core::sensorPoseFromCameraPose(T_world_cam);
	const auto T_shifted = mrpt::poses::CPose3D(0.3, 0, 0, 0, 0, 0) + T_robot;
	EXPECT_GT(grid->computeObservationLikelihood(obs, T_robot), grid->computeObservationLikelihood(obs, T_shifted));

	// A bad value in the INI fails naming the key. (Through the map definition directly:
	// TSetOfMetricMapInitializers leaks the initializer when it throws, which LSan reports.)
	mrpt::config::CConfigFileMemory bad(ini + "\n[map_ismOccupancyGrid2D_00_insertOpts]\nmaxRange = -1\n");
	CISMOccupancyGrid2D::TMapDefinition def;
	try
	{
		def.loadFromConfigFile(bad, "map_ismOccupancyGrid2D_00");
		FAIL() << "expected an exception";
	}
	catch (const std::exception& e)
	{
		EXPECT_NE(std::string(e.what()).find("maxRange"), std::string::npos) << e.what();
	}
}

// A bad value in any of the grid's INI sections throws naming that section and the key; MRPT's
// yes/no booleans and any letter case of rangeNoise are still read.
TEST(CISMOccupancyGrid2D, BadIniValueNamesSectionAndKey)
{
	const std::string prefix = "map_ismOccupancyGrid2D_00";
	keygrid::test::expectBadValuesNameSectionAndKey<CISMOccupancyGrid2D::TMapDefinition>(
		prefix, {
			{"_creationOpts", "resolution = 0"},
			{"_creationOpts", "max_x = -6"},
			{"_insertOpts", "pFree = 1.5"},
			{"_insertOpts", "pFree = 0.6"},
			{"_insertOpts", "freeSpaceModel = bogus"},
			{"_insertOpts", "rangeNoise = laser"},
			{"_insertOpts", "T_world_floor = [1 2]"},
			{"_insertOpts", "floorUpHint = 0 1"},
			{"_insertOpts", "floorRansac_maxTiltDeg = 90"},
			{"_insertOpts", "estimateFloorFromDepth = maybe"},
			{"_insertOpts", "depthDecimation = 1.5"},
			{"_likelihoodOpts", "outlierProbability = 1"}});
	mrpt::config::CConfigFileMemory ini("[" + prefix + "_insertOpts]\nrangeNoise = Constant\nestimateFloorFromDepth = yes\n");
	CISMOccupancyGrid2D::TMapDefinition def;
	def.loadFromConfigFile(ini, prefix);
	EXPECT_EQ(def.insertionOpts.rangeNoise, keygrid::maps::RangeNoiseModel::Constant);
	EXPECT_TRUE(def.insertionOpts.estimateFloorFromDepth);
}

TEST(CISMOccupancyGrid2D, RealKinectFrameLandsInFrontOfTheSensor)
{
	// One real Kinect frame (MRPT depth frame: +X forward, +Z up; sensorPose = identity).
	const std::string path = keygrid::test::mrptDatasetsDir() + "/tests_rgbd.rawlog";
	if (!mrpt::system::fileExists(path)) GTEST_SKIP() << path << " not found (Debian mrpt-common)";
	mrpt::obs::CRawlog log;
	ASSERT_TRUE(log.loadFromRawLogFile(path));
	mrpt::obs::CObservation3DRangeScan::Ptr obs;
	for (size_t i = 0; i < log.size() && !obs; i++)
	{
		if (log.getType(i) == mrpt::obs::CRawlog::etObservation)
			obs = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(log.getAsObservation(i));
		else if (log.getType(i) == mrpt::obs::CRawlog::etSensoryFrame)
			obs = log.getAsObservations(i)->getObservationByClass<mrpt::obs::CObservation3DRangeScan>();
	}
	ASSERT_TRUE(obs);
	CISMOccupancyGrid2D grid;
	grid.insertionOptions.T_world_floor = mrpt::poses::CPose3D(0, 0, -1.0, 0, 0, 0);  // sensor 1 m up
	grid.insertionOptions.obstacleMinHeight = 0.3;
	grid.insertionOptions.obstacleMaxHeight = 2.0;
	ASSERT_TRUE(grid.insertObservation(*obs));
	ASSERT_GT(grid.countStates()[2], 100u);
	// Every observed cell is in front of the sensor (+X) within the 57 degree horizontal field
	// of view (plus discretisation: cells closer than 0.5 m are not checked). A mix-up of the
	// optical and MRPT axes would put them elsewhere.
	const double halfFov = 0.5 * 2.0 * std::atan(0.5 * obs->cameraParams.ncols / obs->cameraParams.fx());
	for (int cy = 0; cy < grid.sizeY(); cy++)
		for (int cx = 0; cx < grid.sizeX(); cx++)
		{
			if (grid.cellState(cx, cy) == CellState::Unknown) continue;
			const double x = grid.idx2x(cx), y = grid.idx2y(cy);
			if (std::hypot(x, y) < 0.5) continue;
			ASSERT_LT(std::abs(std::atan2(y, x)), halfFov + 3.0 * M_PI / 180) << "cell at " << x << "," << y;
		}
}
