// Dynamic objects are where their path says, appear and vanish on time, and fill the mask.
#include <keygrid/sim/Simulator.h>

#include "SimTestScenes.h"
#include "TestData.h"

#include <opencv2/imgproc.hpp>

#include <cmath>

using namespace keygrid;

namespace
{
// Static camera at (0, 0, 1) looking along +x at a wall x = 6. A 0.4 m cube moves from
// y = -1 to y = +1 at x = 3 between t = 0 and t = 2 s and exists only
// during [0, 1.5) s.
std::string movingCubeIni()
{
	return test::wallSceneIni(
		6.0, "noise = false\nmax_incidence_deg = 90",
		"[object.cube]\ntype = box\ncentre = 3 -1 1\nsize = 0.4 0.4 0.4\ndynamic = true\n"
		"path_00 = 0 3 -1 1 0\npath_01 = 2 3 1 1 0\nvisible = 0 1.5\n");
}
}  // namespace

TEST(Dynamic, PathInterpolationAndVisibility)
{
	const sim::Scene scene = test::sceneFromString(
		movingCubeIni() +
		"\n[object.spinner]\ntype = cylinder\ncentre = 0 0 0\nradius = 0.1\nheight = 0.1\ndynamic "
		"= true\npath_00 = 0 3 -1 1 0\npath_01 = 2 3 1 1 90\n");
	const sim::SceneObject* cube = nullptr;
	const sim::SceneObject* spinner = nullptr;
	for (const auto& o : scene.objects)
	{
		if (o.name == "cube") cube = &o;
		if (o.name == "spinner") spinner = &o;
	}
	ASSERT_NE(cube, nullptr);
	ASSERT_NE(spinner, nullptr);
	const Eigen::Isometry3d T = spinner->poseAt(0.5);  // a quarter of the way
	EXPECT_NEAR((T.translation() - Eigen::Vector3d(3, -0.5, 1)).norm(), 0.0, 1e-12);
	EXPECT_NEAR(std::atan2(T.linear()(1, 0), T.linear()(0, 0)), M_PI / 8, 1e-12);
	EXPECT_NEAR((cube->poseAt(-1).translation() - Eigen::Vector3d(3, -1, 1)).norm(), 0.0, 1e-12);
	EXPECT_NEAR((cube->poseAt(5).translation() - Eigen::Vector3d(3, 1, 1)).norm(), 0.0, 1e-12);
	EXPECT_TRUE(cube->visibleAt(0.0));
	EXPECT_TRUE(cube->visibleAt(1.49));
	EXPECT_FALSE(cube->visibleAt(1.5));
}

TEST(Dynamic, RenderedWhereThePathSays)
{
	const sim::Scene scene = test::sceneFromString(movingCubeIni());
	const sim::Simulator simulator(scene, 2);
	const double fx = 131.25, cx = 79.5, cy = 59.5;
	sim::SimFrame f;
	for (double t : {0.5, 1.0, 1.25})
	{
		simulator.view(scene.cameraPose(0), t, 0, f);
		// The path says: centre (3, y, 1) with y = -1 + t (1 m/s along +y), yaw 0, so the face
		// towards the camera is x = 2.8, y - 0.2 .. y + 0.2. Optical x is world -y.
		const double y = -1 + t;
		const int row = static_cast<int>(std::lround(cy));
		const int col = static_cast<int>(std::lround(cx + fx * (-y) / 2.8));
		const int idx = f.render.objectIndex.at<int>(row, col);
		ASSERT_GE(idx, 0) << "t = " << t;
		EXPECT_EQ(scene.objects[idx].name, "cube") << "t = " << t;
		EXPECT_NEAR(f.render.depth.at<float>(row, col), 2.8, 1e-5) << "t = " << t;
		EXPECT_EQ(f.dynamicMask.at<std::uint8_t>(row, col), 255);
		// The face edge away from the optical axis (no side face can show beyond it):
		// the pixel just inside is the cube, the pixel just outside is the wall at 6 m.
		const double farY = y < 0 ? y - 0.2 : y + 0.2;
		const double uEdge = cx + fx * (-farY) / 2.8;
		const int inside =
			static_cast<int>(farY < y ? std::floor(uEdge - 1e-3) : std::ceil(uEdge + 1e-3));
		const int outside =
			static_cast<int>(farY < y ? std::ceil(uEdge + 1e-3) : std::floor(uEdge - 1e-3));
		EXPECT_NEAR(f.render.depth.at<float>(row, inside), 2.8, 1e-5) << "t = " << t;
		EXPECT_NEAR(f.render.depth.at<float>(row, outside), 6.0, 1e-4) << "t = " << t;
		EXPECT_EQ(f.dynamicMask.at<std::uint8_t>(row, outside), 0);
	}
	// Vanished after t = 1.5 s: no dynamic pixel, the wall behind is seen instead.
	simulator.view(scene.cameraPose(0), 1.6, 0, f);
	EXPECT_EQ(cv::countNonZero(f.dynamicMask), 0);
	EXPECT_NEAR(f.render.depth.at<float>(60, 80), 6.0, 1e-4);
}

TEST(Dynamic, OccluderHidesAStaticObjectOnlyWhileItPasses)
{
	// A panel slides in front of the camera between t = 1 s and t = 2 s.
	const std::string ini = test::wallSceneIni(
		6.0, "noise = false\nmax_incidence_deg = 90",
		"[object.panel]\ntype = box\ncentre = 1.5 5 1\nsize = 0.05 1.0 2.0\ndynamic = true\n"
		"path_00 = 1 1.5 5 1\npath_01 = 1.5 1.5 0 1\npath_02 = 2 1.5 -5 1\n");
	const sim::Scene scene = test::sceneFromString(ini);
	const sim::Simulator simulator(scene, 1);
	sim::SimFrame f;
	simulator.view(scene.cameraPose(0), 0.5, 0, f);
	EXPECT_NEAR(f.render.depth.at<float>(60, 80), 6.0, 1e-4);
	simulator.view(scene.cameraPose(0), 1.5, 0, f);
	EXPECT_NEAR(f.render.depth.at<float>(60, 80), 1.475, 1e-4);  // the panel's near face
	EXPECT_EQ(f.dynamicMask.at<std::uint8_t>(60, 80), 255);
	simulator.view(scene.cameraPose(0), 2.5, 0, f);
	EXPECT_NEAR(f.render.depth.at<float>(60, 80), 6.0, 1e-4);
}
