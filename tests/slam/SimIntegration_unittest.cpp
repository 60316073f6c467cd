// The frontend's integration test: keygrid-sim generates a short sequence, keygrid-slam runs the
// shipped config/sim.ini (frontend + both map plugins) on its rawlog, and the trajectory is
// scored against the simulator's exact ground truth.
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/slam/apps/SlamApp.h>
#include <keygrid/maps/CHOCPointsMap.h>
#include <keygrid/maps/OccupancyGridMetrics.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>

#include "SimSlamRun.h"
#include "TestData.h"

using namespace keygrid;

TEST(SimIntegration, ShippedSimConfigTracksAGeneratedSequenceWithMaps)
{
	const auto run = test::renderAndRunSlam(
		test::scratchDir("sim_integration"), "--scene " + test::dataDir() + "/sim/room_arc.ini", true);
	// Kinect-like noise on, exact ground truth. 1 cm: the synthetic sequences' target
	// (doc/evaluation.md, "Trajectory accuracy of the SfM frontend").
	ASSERT_NO_FATAL_FAILURE(test::expectCentimetreRun(run, 90));
	const auto& o = run.options;
	for (const char* f : {"trajectory.txt", "keyframes.txt", "report.json", "map_2d.pgm", "map_2d.yaml", "map_2d.png", "map_3d.bt", "map_3d.ply", "hoc_points.ply", "keyframes.simplemap", "scene.3Dscene"})
		EXPECT_TRUE(mrpt::system::fileExists(o.output + "/" + f)) << f;
	// The 2D map is a valid ROS map_server map with obstacles and free space.
	mrpt::maps::COccupancyGridMap2D grid;
	ASSERT_TRUE(grid.loadFromROSMapServerYAML(o.output + "/map_2d.yaml"));
	int occupied = 0, freeCells = 0;
	for (unsigned y = 0; y < grid.getSizeY(); y++)
		for (unsigned x = 0; x < grid.getSizeX(); x++)
		{
			const float p = grid.getCell(x, y);
			occupied += p < 0.35f;
			freeCells += p > 0.65f;
		}
	EXPECT_GT(occupied, 50);
	// Free space only where the floor was seen (height-band free space).
	EXPECT_GT(freeCells, 300);
	EXPECT_GT(mrpt::system::getFileSize(o.output + "/map_3d.bt"), 1000u);
	// The serialized maps load back as their classes; the HOC map holds as many points as the
	// PLY export.
	for (const auto& [file, cls] : std::vector<std::pair<std::string, std::string>>{
			 {"map_2d.bin", "keygrid::CISMOccupancyGrid2D"}, {"map_3d.bin", "keygrid::CSubmappedOccupancyGrid3D"}, {"hoc_points.bin", "keygrid::CHOCPointsMap"}})
	{
		mrpt::io::CFileGZInputStream in(o.output + "/" + file);
		const auto obj = mrpt::serialization::archiveFrom(in).ReadObject();
		ASSERT_TRUE(obj) << file;
		EXPECT_EQ(std::string(obj->GetRuntimeClass()->className), cls) << file;
		if (const auto hoc = std::dynamic_pointer_cast<CHOCPointsMap>(obj))
		{
			EXPECT_GT(hoc->size(), 100u);
			const std::string ply = test::readTextFile(o.output + "/hoc_points.ply");
			EXPECT_NE(ply.find("element vertex " + std::to_string(hoc->size()) + "\n"), std::string::npos);
		}
	}
}

// keygrid-slam's 2D grid finds the floor from its keyframes: the camera first looks 33 deg
// down (beyond the 25 deg the floor may be tilted against one camera's "up"), then 20 deg; the
// floor is estimated from the pooled depth of the first keyframes with the mean "up" of their
// cameras (the first keyframe's "up" alone would not find it here, and the grid would stay in
// the camera frame). The SLAM world is the first camera frame,
// so the floor frame maps into the sim world (z up, floor z = 0) through the first GT pose.
TEST(SimIntegration, TwoDimensionalGridFindsTheFloorFromKeyframeDepth)
{
	const std::string dir = test::scratchDir("sim_integration_floor");
	const auto run = test::renderAndRunSlam(
		dir, "--scene " + test::dataDir() + "/sim/room_floor_view.ini --voxel-resolution 0", false);
	ASSERT_TRUE(run.rendered) << run.simLog;
	const auto& o = run.options;
	const auto& r = run.result;
	ASSERT_TRUE(r.error.empty()) << r.error;
	EXPECT_EQ(r.tracked, 60u);
	const auto grid = maps::TriStateGrid::loadRosMapServer(o.output + "/map_2d.yaml");
	ASSERT_TRUE(grid.T_world_floor.has_value());
	const auto gt = core::readTumTrajectory(dir + "/seq/groundtruth.txt");
	ASSERT_FALSE(gt.empty());
	const mrpt::poses::CPose3D T_sim_floor = gt.front().T_world_cam + *grid.T_world_floor;
	// The floor estimate's target: 2 cm and 1 deg (doc/evaluation.md, Summary, "floor estimate").
	EXPECT_NEAR(T_sim_floor.z(), 0.0, 0.02);
	const auto R = T_sim_floor.getRotationMatrix();
	EXPECT_GT(R(2, 2), std::cos(1.0 * M_PI / 180.0));  // floor normal vs world z
}
