// The maps of a run come from the INI's [MappingApplication] section, keygrid's plugins and
// MRPT's own maps alike; mistakes that MRPT would ignore are reported by name.
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <keygrid/slam/MetricMaps.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/COccupancyGridMap2D.h>

#include "TestData.h"

#include <stdexcept>

using namespace keygrid;

namespace
{
/** The INI of one submapped 3D grid of 5 cm voxels. */
const char* const kGrid3dIni =
	"[MappingApplication]\nsubmappedOccupancyGrid3D_count = 1\n"
	"[MappingApplication_submappedOccupancyGrid3D_00_creationOpts]\nresolution = 0.05\n";

/** Log-odds of the voxel on the optical axis of a camera at the origin (world z), z ahead (0:
 * unknown). The point is inside the voxel, 1 cm off the axis, clear of its faces. */
float onAxis(const CSubmappedOccupancyGrid3D& g, double z)
{
	return g.logOddsAt(mrpt::math::TPoint3D(0.01, 0.01, z)).value_or(0.f);
}

/** Inserts keyframe `id` (at the origin, facing something 2.02-2.025 m ahead on its axis) into
 * `maps` and checks the 3D grid: occupied in the voxel [2.00, 2.05) ahead, free at 1 m, nothing
 * known beyond. Returns the grid. */
const CSubmappedOccupancyGrid3D& insertFacingAPoint2mAhead(slam::MetricMaps& maps, const sfm::SparseMap& map, sfm::KeyFrameId id)
{
	maps.insertKeyFrame(map, id, 0.0);
	const auto g3 = maps.maps().mapByClass<CSubmappedOccupancyGrid3D>();
	if (!g3) throw std::logic_error("no submappedOccupancyGrid3D among the maps");
	EXPECT_GT(onAxis(*g3, 2.025), 0.f);
	EXPECT_LT(onAxis(*g3, 1.025), 0.f);
	EXPECT_EQ(onAxis(*g3, 2.525), 0.f);  // never observed
	return *g3;
}
}  // namespace

TEST(MetricMaps, CreatesOurPluginsAndMrptMapsFromTheIni)
{
	mrpt::config::CConfigFileMemory ini(
		"[MappingApplication]\n"
		"ismOccupancyGrid2D_count = 1\n"
		"submappedOccupancyGrid3D_count = 1\n"
		"occupancyGrid_count = 1\n"
		"[MappingApplication_ismOccupancyGrid2D_00_creationOpts]\n"
		"resolution = 0.10\n");
	const slam::MetricMaps maps(ini, {});
	ASSERT_EQ(maps.size(), 3u);
	int ism = 0, g3 = 0, mrptGrid = 0;
	for (const auto& m : maps.maps().maps)
	{
		if (auto* p = dynamic_cast<const CISMOccupancyGrid2D*>(m.get()))
		{
			++ism;
			EXPECT_DOUBLE_EQ(p->resolution(), 0.10);
		}
		g3 += dynamic_cast<const CSubmappedOccupancyGrid3D*>(m.get()) != nullptr;
		mrptGrid += dynamic_cast<const mrpt::maps::COccupancyGridMap2D*>(m.get()) != nullptr;
	}
	EXPECT_EQ(ism, 1);
	EXPECT_EQ(g3, 1);
	EXPECT_EQ(mrptGrid, 1);
}

TEST(MetricMaps, UnknownMapTypeIsNamed)
{
	mrpt::config::CConfigFileMemory ini("[MappingApplication]\nismOccupancyGrid2d_count = 1\n");
	try
	{
		slam::MetricMaps maps(ini, {});
		FAIL() << "a misspelt map type must not be ignored";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("ismOccupancyGrid2d_count"), std::string::npos) << e.what();
	}
	mrpt::config::CConfigFileMemory none("[slam]\nmode = sequential\n");
	EXPECT_TRUE(slam::MetricMaps(none, {}).empty());
	slam::MapFeedOptions feed;
	mrpt::config::CConfigFileMemory bad("[maps]\nism2d_input = sometimes\n");
	EXPECT_THROW(feed.loadFromConfigFile(bad, "maps"), std::invalid_argument);
}

TEST(MetricMaps, EveryTwoDimensionalGridTakesTheRunsFloorFrame)
{
	// Given in [floor]: the 2D grid's floor is that pose from the start.
	mrpt::config::CConfigFileMemory ini(
		"[MappingApplication]\nismOccupancyGrid2D_count = 1\nsubmappedOccupancyGrid3D_count = 1\n");
	maps::FloorFrameOptions floor;
	floor.givenPose = "[0.1 1.2 0.3 0 -90 90]";
	const slam::MetricMaps given(ini, {}, floor);
	ASSERT_TRUE(given.T_world_floor());
	EXPECT_TRUE(given.floor().given());
	const auto* ism = given.maps().mapByClass<CISMOccupancyGrid2D>().get();
	ASSERT_TRUE(ism);
	EXPECT_TRUE(ism->externalFloor());
	EXPECT_TRUE(ism->floorKnown());
	EXPECT_LT((ism->floorPose().asTPose() - given.T_world_floor()->asTPose()).norm(), 1e-12);
	EXPECT_NE(given.floor().toJson().find("\"source\": \"given\""), std::string::npos);

	// Estimated: unknown until the first keyframes, and the grid does not estimate its own.
	const slam::MetricMaps estimated(ini, {});
	EXPECT_FALSE(estimated.T_world_floor());
	const auto* ism2 = estimated.maps().mapByClass<CISMOccupancyGrid2D>().get();
	ASSERT_TRUE(ism2);
	EXPECT_FALSE(ism2->floorKnown());
	EXPECT_NE(estimated.floor().toJson().find("\"source\": \"none\""), std::string::npos);

	// A floor pose of the grid's own would be silently replaced: refused, naming the key.
	mrpt::config::CConfigFileMemory own(
		"[MappingApplication]\nismOccupancyGrid2D_count = 1\n"
		"[MappingApplication_ismOccupancyGrid2D_00_insertOpts]\nT_world_floor = [0 0 -1 0 0 0]\n");
	try
	{
		slam::MetricMaps m(own, {});
		FAIL() << "a grid's own T_world_floor must not be ignored";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("[floor] T_world_floor"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find("_insertOpts] T_world_floor"), std::string::npos) << e.what();
	}
}

TEST(MetricMaps, AKeyFrameEntersTheGridsAndACorrectionMovesItThere)
{
	// One keyframe at the origin facing a flat wall 2.02 m ahead (optical frame: z forward):
	// the 3D grid holds the wall in the voxel [2.00, 2.05) on the axis and free space before
	// it. Corrected 0.5 m forward, the wall is in [2.50, 2.55) and its former voxel is free.
	slam::MetricMaps maps(mrpt::config::CConfigFileMemory(kGrid3dIni), {});
	sfm::SparseMap map;
	sfm::KeyFrame kf;
	auto& cam = kf.features.camera;
	cam.width = 64;
	cam.height = 48;
	cam.fx = cam.fy = 50.0;
	cam.cx = 31.5;
	cam.cy = 23.5;
	kf.depth = cv::Mat(48, 64, CV_32F, cv::Scalar(2.02f));
	const sfm::KeyFrameId id = map.addKeyFrame(std::move(kf)).id;
	const auto& g3 = insertFacingAPoint2mAhead(maps, map, id);
	const auto logOdds = [&](double z) { return onAxis(g3, z); };

	const auto times = maps.applyCorrection({{id, mrpt::poses::CPose3D(0, 0, 0.5, 0, 0, 0)}});
	EXPECT_EQ(times.count(CSubmappedOccupancyGrid3D::GetRuntimeClassIdStatic().className), 1u);
	EXPECT_GT(logOdds(2.525), 0.f);
	EXPECT_LT(logOdds(2.025), 0.f);
	EXPECT_LT(logOdds(1.525), 0.f);
}

TEST(MetricMaps, AMonocularKeyFramesMapPointsEnterThe3DGridAndFollowItsScale)
{
	// A keyframe without depth at the origin with one landmark on its optical axis, 2.025 map
	// units ahead: the 3D grid holds it in the voxel [2.00, 2.05) and free space before it. A
	// Sim(3) correction that keeps the keyframe's pose and gives it scale 1.25 puts the point
	// 2.53 ahead, in [2.50, 2.55), its former voxel on the free part of the ray.
	slam::MetricMaps maps(mrpt::config::CConfigFileMemory(kGrid3dIni), {});
	sfm::SparseMap map;
	sfm::KeyFrame kf;
	kf.features.keypoints.resize(1);
	kf.features.undistorted.resize(1);
	kf.features.depth.assign(1, 0.f);
	kf.features.descriptors = cv::Mat(1, 32, CV_8U, cv::Scalar(0));
	kf.features.levelScale = {1.0};
	const sfm::KeyFrameId id = map.addKeyFrame(std::move(kf)).id;
	map.addLandmark({0.0, 0.0, 2.025}, id, 0);
	const auto& g3 = insertFacingAPoint2mAhead(maps, map, id);
	const auto logOdds = [&](double z) { return onAxis(g3, z); };

	const auto times = maps.applyCorrection({{id, mrpt::poses::CPose3D()}}, {{id, 1.25}});
	EXPECT_EQ(times.count(CSubmappedOccupancyGrid3D::GetRuntimeClassIdStatic().className), 1u);
	EXPECT_GT(logOdds(2.525), 0.f);
	EXPECT_LT(logOdds(2.025), 0.f);
	EXPECT_THROW(maps.applyCorrection({{id, mrpt::poses::CPose3D()}}, {{id, -1.0}}), std::invalid_argument);
}
