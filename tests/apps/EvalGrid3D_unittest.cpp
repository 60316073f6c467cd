// keygrid-eval's 3D grid mode run as a user would: a map_3d.bt written the way keygrid-slam
// writes it (floor frame in its header) scored against occupancy_voxels.txt through the
// trajectory alignment (answers counted in the comments), the seen mask rendered from a shipped
// scene, and the bad-input messages.
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/maps/ExportFrame.h>
#include <keygrid/maps/OctomapBinaryWriter.h>
#include <keygrid/sim/GroundTruthOccupancy.h>
#include <keygrid/sim/Scene.h>

#include "EvalScenes.h"
#include "TestData.h"

#include <cmath>
#include <fstream>

using keygrid::test::jsonNumber;
using keygrid::test::runCommand;

namespace
{
constexpr double kRes = 0.05;
const std::string kScene = "/config/sim/room_loop.ini";

/** room_loop's ground-truth camera path (dir/gt.txt) and every 50th frame (dir/kf.txt). */
keygrid::core::Trajectory sceneTrajectory(const std::string& dir)
{
	return keygrid::test::writeSceneTrajectory(keygrid::sim::Scene::loadFromFile(keygrid::test::sourceDir() + kScene), dir);
}

/** Voxel (i, j, k) of the ground-truth world as a voxel of the frame T_frame_gt maps it into. */
std::array<int, 3> voxelIn(const mrpt::poses::CPose3D& T_frame_gt, int i, int j, int k)
{
	const auto c = T_frame_gt.composePoint(mrpt::math::TPoint3D((i + 0.5) * kRes, (j + 0.5) * kRes, (k + 0.5) * kRes));
	return {int(std::floor(c.x / kRes)), int(std::floor(c.y / kRes)), int(std::floor(c.z / kRes))};
}

void writeBt(const std::string& path, keygrid::maps::OctomapBinaryWriter& bt, const std::string& comment)
{
	std::ofstream f(path, std::ios::binary);
	bt.write(f, kRes, comment);
}
}  // namespace

TEST(EvalTool, Grid3DModeScoresTheMapInItsFloorFrameThroughTheAlignment)
{
	const std::string dir = keygrid::test::scratchDir("eval_grid3d");
	// Truth: a wall of 20 x 20 voxels at x index 10. The SLAM world differs from the
	// ground-truth world by a rigid motion; the map's floor frame is the ground-truth world turned
	// 90 deg about z and moved by whole voxels, so every voxel has one exact image.
	keygrid::sim::VoxelSet truth(kRes, Eigen::Vector3d::Zero());
	for (int k = 0; k < 20; k++)
		for (int j = 0; j < 20; j++) truth.insert({10, j, k});
	truth.finalize();
	truth.save(dir + "/voxels.txt");
	const mrpt::poses::CPose3D T_gt_floor(0.50, 0.25, 0.0, M_PI / 2, 0, 0), T_est_gt(1.0, -2.0, 0.5, 0.7, 0.2, -0.1);
	const auto gt = sceneTrajectory(dir);
	keygrid::core::Trajectory est;
	for (const auto& p : gt) est.push_back({p.t, T_est_gt + p.T_world_cam});
	keygrid::core::writeTumTrajectory(dir + "/est.txt", est);
	// Map: rows j < 10 of the wall occupied; free in front of the wall (x index 9) and through
	// its rows j >= 15 (100 true voxels called free, none with a map voxel within one voxel).
	const auto T_floor_gt = -T_gt_floor;
	keygrid::maps::OctomapBinaryWriter bt;
	for (int k = 0; k < 20; k++)
		for (int j = 0; j < 20; j++)
		{
			const auto wall = voxelIn(T_floor_gt, 10, j, k), front = voxelIn(T_floor_gt, 9, j, k);
			if (j < 10 || j >= 15) bt.add(wall[0], wall[1], wall[2], j < 10);
			bt.add(front[0], front[1], front[2], false);
		}
	writeBt(dir + "/map_3d.bt", bt, keygrid::maps::floorFrameComment(T_est_gt + T_gt_floor));

	const std::string tool = keygrid::test::toolPath("keygrid-eval");
	std::string out;
	ASSERT_EQ(runCommand(tool + " --gt " + dir + "/gt.txt --est " + dir + "/est.txt --grid3d " + dir + "/map_3d.bt --voxels " +
			dir + "/voxels.txt --json " + dir + "/e.json", &out), 0) << out;
	const std::string j = keygrid::test::readTextFile(dir + "/e.json");
	EXPECT_NEAR(jsonNumber(j, "ate_rmse_m"), 0.0, 1e-6) << j;
	EXPECT_EQ(jsonNumber(j, "grid3d_occupied_voxels"), 200);
	EXPECT_EQ(jsonNumber(j, "grid3d_free_voxels"), 500);
	EXPECT_DOUBLE_EQ(jsonNumber(j, "grid3d_precision"), 1.0);
	EXPECT_EQ(jsonNumber(j, "grid3d_true_voxels"), 400);
	// Rows 0..9 and, within one voxel, row 10: 220 of 400.
	EXPECT_DOUBLE_EQ(jsonNumber(j, "grid3d_recall"), 0.55);
	EXPECT_DOUBLE_EQ(jsonNumber(j, "grid3d_recall_seen"), 0.55);  // no seen mask
	EXPECT_EQ(jsonNumber(j, "grid3d_true_called_free"), 100);
	EXPECT_EQ(jsonNumber(j, "grid3d_hazard_voxels"), 100);
	EXPECT_NE(j.find("\"grid3d_floor_frame\": true"), std::string::npos) << j;
	EXPECT_NE(out.find("hazard voxels (called free, no map voxel within the tolerance) 100"), std::string::npos) << out;
}

TEST(EvalTool, Grid3DModeSeenMaskFromAShippedScene)
{
	// room_loop's true voxels as the map itself, in the ground-truth world (no floor line), and 9
	// keyframes rendered at their ground-truth poses.
	const std::string dir = keygrid::test::scratchDir("eval_grid3d_scene");
	const auto scene = keygrid::sim::Scene::loadFromFile(keygrid::test::sourceDir() + kScene);
	const auto truth = keygrid::sim::voxeliseStaticScene(scene, kRes);
	truth.save(dir + "/voxels.txt");
	keygrid::maps::OctomapBinaryWriter bt;
	for (const auto& v : truth.voxels()) bt.add(v[0], v[1], v[2], true);
	writeBt(dir + "/map_3d.bt", bt, "");
	sceneTrajectory(dir);
	const std::string tool = keygrid::test::toolPath("keygrid-eval");
	std::string out;
	ASSERT_EQ(runCommand(tool + " --quiet --gt " + dir + "/gt.txt --est " + dir + "/gt.txt --grid3d " + dir +
			"/map_3d.bt --voxels " + dir + "/voxels.txt --scene " + keygrid::test::sourceDir() + kScene + " --keyframes " +
			dir + "/kf.txt --json " + dir + "/e.json", &out), 0) << out;
	const std::string j = keygrid::test::readTextFile(dir + "/e.json");
	EXPECT_EQ(jsonNumber(j, "grid3d_visibility_keyframes"), 9) << j;
	EXPECT_NE(j.find("\"grid3d_floor_frame\": false"), std::string::npos) << j;
	EXPECT_DOUBLE_EQ(jsonNumber(j, "grid3d_precision"), 1.0);
	EXPECT_DOUBLE_EQ(jsonNumber(j, "grid3d_recall"), 1.0);
	EXPECT_DOUBLE_EQ(jsonNumber(j, "grid3d_recall_seen"), 1.0);
	EXPECT_EQ(jsonNumber(j, "grid3d_hazard_voxels"), 0);
	// The cameras circle inside the room within 4 m: they see part of the surfaces.
	const double seen = jsonNumber(j, "grid3d_true_voxels_seen");
	EXPECT_GT(seen, 2000);
	EXPECT_LT(seen, static_cast<double>(truth.size()));
}

TEST(EvalTool, Grid3DModeBadInputsGiveOneLineReasons)
{
	const std::string dir = keygrid::test::scratchDir("eval_grid3d_bad");
	sceneTrajectory(dir);
	keygrid::sim::VoxelSet(kRes, Eigen::Vector3d::Zero()).save(dir + "/voxels.txt");
	const std::string base = keygrid::test::toolPath("keygrid-eval") + " --gt " + dir + "/gt.txt --est " + dir + "/gt.txt";
	std::string out;
	EXPECT_EQ(runCommand(base + " --grid3d " + dir + "/map_3d.bt", &out), 2);
	EXPECT_NE(out.find("--grid3d needs --voxels"), std::string::npos) << out;
	EXPECT_EQ(runCommand(base + " --voxels " + dir + "/voxels.txt", &out), 2);
	EXPECT_NE(out.find("--voxels needs --grid3d"), std::string::npos) << out;
	EXPECT_EQ(runCommand(base + " --keyframes " + dir + "/kf.txt", &out), 2);
	EXPECT_NE(out.find("--keyframes needs --map or --grid3d"), std::string::npos) << out;
	const std::string grid = base + " --grid3d " + dir + "/missing.bt --voxels " + dir + "/voxels.txt";
	EXPECT_EQ(runCommand(grid + " --scene x.ini", &out), 2);
	EXPECT_NE(out.find("--scene and --keyframes go together"), std::string::npos) << out;
	EXPECT_EQ(runCommand(grid + " --voxel-max-range 0", &out), 2);
	EXPECT_NE(out.find("maxRange must be > 0"), std::string::npos) << out;
	EXPECT_EQ(runCommand(grid, &out), 1);
	EXPECT_NE(out.find("missing.bt' does not exist"), std::string::npos) << out;
	std::ofstream(dir + "/text.bt") << "not a map\n";
	EXPECT_EQ(runCommand(base + " --grid3d " + dir + "/text.bt --voxels " + dir + "/voxels.txt", &out), 1);
	EXPECT_NE(out.find("is not an OctoMap binary file"), std::string::npos) << out;
}
