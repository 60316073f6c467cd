// keygrid-eval's map mode run as a user would: keygrid-slam's map_2d scored against keygrid-sim's
// floor plan through the trajectory alignment (hand-made files whose answers are counted in the
// comments), the visibility mask rendered from a shipped scene, and the bad-input messages.
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/sim/GroundTruthOccupancy.h>
#include <keygrid/sim/Scene.h>
#include <mrpt/math/CQuaternion.h>

#include "EvalScenes.h"
#include "TestData.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>

using keygrid::test::jsonNumber;
using keygrid::test::runCommand;

namespace
{
/** Writes a map_2d.yaml/.pgm pair the way keygrid-slam does (first line: the floor pose in the
 * SLAM world), cells of `resolution` from (0, 0) in the floor frame; state(cx, cy): 0 occupied,
 * 254 free, 205 unknown. */
void writeMap(
	const std::string& stem, int w, int h, const std::function<unsigned char(int, int)>& state,
	const mrpt::poses::CPose3D* T_world_floor, double resolution = 0.05)
{
	std::ofstream yaml(stem + ".yaml");
	if (T_world_floor)
	{
		mrpt::math::CQuaternionDouble q;
		T_world_floor->getAsQuaternion(q);
		char b[256];
		std::snprintf(b, sizeof(b), "# keygrid T_world_floor (x y z qx qy qz qw): %.12f %.12f %.12f %.12f %.12f %.12f %.12f\n",
			T_world_floor->x(), T_world_floor->y(), T_world_floor->z(), q.x(), q.y(), q.z(), q.r());
		yaml << b;
	}
	const std::string image = stem.substr(stem.find_last_of('/') + 1) + ".pgm";
	yaml << "image: " << image << "\nresolution: " << resolution << "\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.35\n";
	std::ofstream pgm(stem + ".pgm", std::ios::binary);
	pgm << "P5\n" << w << " " << h << "\n255\n";
	for (int r = 0; r < h; r++)
		for (int cx = 0; cx < w; cx++) pgm.put(static_cast<char>(state(cx, h - 1 - r)));
}

/** A 1.5 s trajectory circling at ~1.3 m, 30 Hz, and the same seen from a SLAM world whose
 * unit is 1 / estScale m (a monocular map's arbitrary unit: positions multiplied by estScale). */
void writeTrajectories(const std::string& dir, const mrpt::poses::CPose3D& T_est_gt, double estScale = 1.0)
{
	keygrid::core::Trajectory gt, est;
	for (int i = 0; i < 45; i++)
	{
		const double t = 1700000000.0 + i / 30.0, a = 0.15 * i;
		const mrpt::poses::CPose3D p(0.5 + 0.3 * std::cos(a), 0.5 + 0.3 * std::sin(a), 1.3 + 0.1 * std::sin(2 * a), a, 0.2, -1.7);
		gt.push_back({t, p});
		mrpt::poses::CPose3D e = T_est_gt + p;
		e.x(e.x() * estScale), e.y(e.y() * estScale), e.z(e.z() * estScale);
		est.push_back({t, e});
	}
	keygrid::core::writeTumTrajectory(dir + "/gt.txt", gt);
	keygrid::core::writeTumTrajectory(dir + "/est.txt", est);
}
}  // namespace

TEST(EvalTool, MapModeCountsHazardsRecallAndFreeF1ThroughTheAlignment)
{
	const std::string dir = keygrid::test::scratchDir("eval_map");
	// Plan: 20 x 20 cells of 5 cm, a 6 x 6 obstacle at cells 7..12: 36 cells, 16 interior
	// (8..11: no free cell among their 8 neighbours), 20 on the boundary; 364 free.
	keygrid::sim::FloorPlan fp;
	fp.width = fp.height = 20;
	fp.occupied.assign(400, 0);
	auto inBlock = [](int c, int lo, int hi) { return c >= lo && c <= hi; };
	for (int cy = 7; cy <= 12; cy++)
		for (int cx = 7; cx <= 12; cx++) fp.occupied[cy * 20 + cx] = 1;
	fp.save(dir + "/plan");
	// The SLAM world differs from the ground-truth world by a 3D rigid motion; the map's floor
	// frame is the ground-truth world seen from the SLAM world, so after alignment the map lies
	// exactly on the plan. Map: the obstacle's ring occupied, its interior FREE (16 hazards),
	// everything else free.
	const mrpt::poses::CPose3D T_est_gt(1.0, -2.0, 0.5, 0.7, 0.2, -0.1);
	writeTrajectories(dir, T_est_gt);
	writeMap(dir + "/map_2d", 20, 20,
		[&](int cx, int cy) -> unsigned char {
			const bool block = inBlock(cx, 7, 12) && inBlock(cy, 7, 12);
			const bool interior = inBlock(cx, 8, 11) && inBlock(cy, 8, 11);
			return block && !interior ? 0 : 254;
		},
		&T_est_gt);
	const std::string tool = keygrid::test::toolPath("keygrid-eval");
	std::string out;
	ASSERT_EQ(runCommand(tool + " --gt " + dir + "/gt.txt --est " + dir + "/est.txt --map " + dir +
			"/map_2d.yaml --floorplan " + dir + "/plan.yaml --overlay " + dir + "/overlay.png --json " + dir + "/e.json",
			&out), 0) << out;
	const std::string j = keygrid::test::readTextFile(dir + "/e.json");
	EXPECT_NEAR(jsonNumber(j, "ate_rmse_m"), 0.0, 1e-6) << j;
	EXPECT_EQ(jsonNumber(j, "map_hazard_cells"), 16);
	EXPECT_EQ(jsonNumber(j, "map_interior_obstacle_cells"), 16);
	EXPECT_EQ(jsonNumber(j, "map_obstacle_called_free_cells"), 16);
	EXPECT_EQ(jsonNumber(j, "map_boundary_cells_seen"), 20);
	EXPECT_DOUBLE_EQ(jsonNumber(j, "map_boundary_recall"), 1.0);
	EXPECT_DOUBLE_EQ(jsonNumber(j, "map_obstacle_precision"), 1.0);
	// Interior cells next to the ring match within 5 cm; the 4 central ones do not.
	EXPECT_NEAR(jsonNumber(j, "map_obstacle_recall"), 32.0 / 36.0, 1e-6);
	// Free: 364 + 16 cells called free, 364 correct; every GT-free cell called free.
	EXPECT_NEAR(jsonNumber(j, "map_free_precision"), 364.0 / 380.0, 1e-6);
	EXPECT_DOUBLE_EQ(jsonNumber(j, "map_free_recall"), 1.0);
	EXPECT_NEAR(jsonNumber(j, "map_free_f1"), 728.0 / 744.0, 1e-6);
	EXPECT_NEAR(jsonNumber(j, "map_floor_offset_m"), 0.0, 1e-6);
	EXPECT_NEAR(jsonNumber(j, "map_floor_tilt_deg"), 0.0, 1e-4);
	EXPECT_EQ(jsonNumber(j, "map_visibility_keyframes"), 0);
	EXPECT_NE(out.find("hazard cells 16"), std::string::npos) << out;
	std::ifstream png(dir + "/overlay.png", std::ios::binary);
	char magic[4] = {};
	png.read(magic, 4);
	EXPECT_EQ(std::string(magic + 1, 3), "PNG");
}

TEST(EvalTool, MapModeWithSim3ScoresAMapInTheEstimatesOwnUnit)
{
	// The plan of the test above (a 6 x 6 obstacle in 20 x 20 cells of 5 cm); the SLAM world is
	// rotated, moved and in half-metres (a monocular run without a metric scale): its map has
	// the plan's cells at 2.5 cm, and its floor frame's origin is at half the distance.
	const std::string dir = keygrid::test::scratchDir("eval_map_sim3");
	keygrid::sim::FloorPlan fp;
	fp.width = fp.height = 20;
	fp.occupied.assign(400, 0);
	auto inBlock = [](int cx, int cy) { return cx >= 7 && cx <= 12 && cy >= 7 && cy <= 12; };
	for (int cy = 0; cy < 20; cy++)
		for (int cx = 0; cx < 20; cx++) fp.occupied[cy * 20 + cx] = inBlock(cx, cy);
	fp.save(dir + "/plan");
	const mrpt::poses::CPose3D T_est_gt(1.0, -2.0, 0.5, 0.7, 0.2, -0.1);
	writeTrajectories(dir, T_est_gt, 0.5);
	mrpt::poses::CPose3D T_world_floor = T_est_gt;
	T_world_floor.x(0.5), T_world_floor.y(-1.0), T_world_floor.z(0.25);
	writeMap(dir + "/map_2d", 20, 20, [&](int cx, int cy) -> unsigned char { return inBlock(cx, cy) ? 0 : 254; },
		&T_world_floor, 0.025);
	const std::string tool = keygrid::test::toolPath("keygrid-eval");
	const std::string base = tool + " --gt " + dir + "/gt.txt --est " + dir + "/est.txt --map " + dir +
		"/map_2d.yaml --floorplan " + dir + "/plan.yaml --json " + dir + "/e.json";
	std::string out;
	ASSERT_EQ(runCommand(base + " --sim3", &out), 0) << out;
	std::string j = keygrid::test::readTextFile(dir + "/e.json");
	EXPECT_NEAR(jsonNumber(j, "ate_rmse_m"), 0.0, 1e-6) << j;
	EXPECT_EQ(jsonNumber(j, "map_hazard_cells"), 0);
	EXPECT_DOUBLE_EQ(jsonNumber(j, "map_obstacle_recall"), 1.0);
	EXPECT_DOUBLE_EQ(jsonNumber(j, "map_obstacle_precision"), 1.0);
	EXPECT_DOUBLE_EQ(jsonNumber(j, "map_free_f1"), 1.0);
	EXPECT_NEAR(jsonNumber(j, "map_floor_offset_m"), 0.0, 1e-6);
	EXPECT_NEAR(jsonNumber(j, "map_floor_tilt_deg"), 0.0, 1e-4);
	// A rigid alignment leaves the map at half size on the plan: part of the plan's obstacle
	// lies under the map's free cells.
	ASSERT_EQ(runCommand(base, &out), 0) << out;
	j = keygrid::test::readTextFile(dir + "/e.json");
	EXPECT_GT(jsonNumber(j, "map_hazard_cells"), 0) << j;
}

TEST(EvalTool, MapModeVisibilityFromAShippedScene)
{
	// room_loop's plan and 9 keyframes at its ground-truth poses; the map is the plan itself
	// (obstacles occupied, the rest free), in the ground-truth world.
	const std::string dir = keygrid::test::scratchDir("eval_map_scene");
	const std::string scenePath = keygrid::test::sourceDir() + "/config/sim/room_loop.ini";
	const auto scene = keygrid::sim::Scene::loadFromFile(scenePath);
	const auto fp = keygrid::sim::floorPlanOfStaticScene(scene, 0.05, 0.1, 1.8);
	fp.save(dir + "/plan");
	keygrid::test::writeSceneTrajectory(scene, dir);
	const mrpt::poses::CPose3D I;
	// The map's lattice starts at (0, 0); the plan's may start one cell lower.
	const int ox = static_cast<int>(std::lround(fp.origin.x() / 0.05)), oy = static_cast<int>(std::lround(fp.origin.y() / 0.05));
	writeMap(dir + "/map_2d", fp.width + ox, fp.height + oy,
		[&](int cx, int cy) -> unsigned char { return fp.occupiedAt(cx - ox, cy - oy) ? 0 : 254; }, &I);
	const std::string tool = keygrid::test::toolPath("keygrid-eval");
	std::string out;
	ASSERT_EQ(runCommand(tool + " --quiet --gt " + dir + "/gt.txt --est " + dir + "/gt.txt --map " + dir +
			"/map_2d.yaml --floorplan " + dir + "/plan.yaml --scene " + scenePath + " --keyframes " + dir +
			"/kf.txt --json " + dir + "/e.json", &out), 0) << out;
	const std::string j = keygrid::test::readTextFile(dir + "/e.json");
	EXPECT_EQ(jsonNumber(j, "map_visibility_keyframes"), 9) << j;
	EXPECT_EQ(jsonNumber(j, "map_hazard_cells"), 0);
	EXPECT_DOUBLE_EQ(jsonNumber(j, "map_boundary_recall"), 1.0);
	EXPECT_DOUBLE_EQ(jsonNumber(j, "map_obstacle_precision"), 1.0);
	EXPECT_DOUBLE_EQ(jsonNumber(j, "map_free_f1"), 1.0);
	// The cameras circle inside the room: they see part of the obstacle boundary (never the
	// walls behind the shelf and cabinet) and a part of the free floor.
	const double seen = jsonNumber(j, "map_boundary_cells_seen"), free = jsonNumber(j, "map_free_cells_seen");
	EXPECT_GT(seen, 300);
	EXPECT_LT(seen, static_cast<double>(fp.occupiedCount()));
	EXPECT_GT(free, 3000);
	EXPECT_LT(free, static_cast<double>(fp.width * fp.height) - fp.occupiedCount());
}

TEST(EvalTool, MapModeBadInputsGiveOneLineReasons)
{
	const std::string dir = keygrid::test::scratchDir("eval_map_bad");
	writeTrajectories(dir, mrpt::poses::CPose3D());
	keygrid::sim::FloorPlan fp;
	fp.width = fp.height = 4;
	fp.occupied.assign(16, 0);
	fp.save(dir + "/plan");
	writeMap(dir + "/nofloor", 4, 4, [](int, int) -> unsigned char { return 254; }, nullptr);
	const std::string tool = keygrid::test::toolPath("keygrid-eval");
	const std::string base = tool + " --gt " + dir + "/gt.txt --est " + dir + "/est.txt";
	std::string out;
	EXPECT_EQ(runCommand(base + " --map " + dir + "/nofloor.yaml", &out), 2);
	EXPECT_NE(out.find("--map needs --floorplan"), std::string::npos) << out;
	EXPECT_EQ(runCommand(base + " --overlay " + dir + "/o.png", &out), 2);
	EXPECT_NE(out.find("--overlay needs --map"), std::string::npos) << out;
	EXPECT_EQ(runCommand(base + " --map " + dir + "/nofloor.yaml --floorplan " + dir + "/plan.yaml --scene x.ini", &out), 2);
	EXPECT_NE(out.find("--scene and --keyframes go together"), std::string::npos) << out;
	EXPECT_EQ(runCommand(base + " --map " + dir + "/nofloor.yaml --floorplan " + dir + "/plan.yaml", &out), 1);
	EXPECT_NE(out.find("nofloor.yaml' has no '# keygrid T_world_floor' line"), std::string::npos) << out;
	EXPECT_EQ(runCommand(base + " --map " + dir + "/nofloor.yaml --floorplan " + dir + "/missing.yaml", &out), 1);
	EXPECT_NE(out.find("missing.yaml' does not exist"), std::string::npos) << out;
	EXPECT_EQ(runCommand(base + " --map " + dir + "/nofloor.yaml --floorplan " + dir + "/plan.yaml --tolerance -1", &out), 2);
	EXPECT_NE(out.find("matchTolerance must be >= 0"), std::string::npos) << out;
}
