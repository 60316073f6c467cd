// The rolling-shutter renderer: every row of a rolling-shutter frame is exactly that row of a
// global-shutter render from the pose (and object time) of the row's exposure; a zero readout
// is the global-shutter render.
#include <keygrid/sim/Simulator.h>
#include <opencv2/core.hpp>

#include "SimTestScenes.h"

#include <gtest/gtest.h>

using namespace keygrid;

namespace
{
/** A fast pan (90 deg in 1 s) across a floor, a wall and a box that moves. */
std::string panSceneIni(double readout)
{
	return "[scene]\nseed = 2\nframes = 30\nrate_hz = 30\n" + test::tinyCameraIni() +
		   "[sensor]\nnoise = false\nmax_incidence_deg = 90\nmax_range = 10\nrolling_shutter_readout = " + std::to_string(readout) +
		   "\n[trajectory]\nwp_00 = 0 0 1.2  3 -3 0.8\nwp_01 = 0.1 0 1.2  3 3 0.8\n"
		   "[object.floor]\ntype = quad\ncorner = -5 -6 0\nedge1 = 12 0 0\nedge2 = 0 14 0\ntexture = checker\n"
		   "[object.wall]\ntype = quad\ncorner = 4 -6 0\nedge1 = 0 14 0\nedge2 = 0 0 5\ntexture = blobs\n"
		   "[object.box]\ntype = box\ncentre = 2.5 0.5 0.5\nsize = 0.6 0.8 1.0\nyaw = 31\n"
		   "dynamic = true\npath_00 = 0 2.5 0.0 0.5\npath_01 = 1 2.5 0.8 0.5\n";
}

bool rowsEqual(const cv::Mat& a, const cv::Mat& b, int y) { return cv::countNonZero(a.row(y).reshape(1) != b.row(y).reshape(1)) == 0; }
}  // namespace

TEST(RollingShutterRender, EachRowIsTheGlobalShutterRowAtItsExposureTime)
{
	const double readout = 0.03;
	const auto scene = test::sceneFromString(panSceneIni(readout));
	const sim::Renderer renderer(scene);
	const double t = scene.frameTime(15);
	const auto poseAt = [&](double ti) { return sim::Renderer::toIsometry(scene.trajectory.poseAt(ti)); };
	sim::RenderOutput rs, gs, mid;
	renderer.renderRollingShutter(poseAt, t, readout, rs);
	renderer.render(poseAt(t), t, mid);
	const int H = static_cast<int>(scene.camera.height);
	int differsFromMid = 0;
	for (int y : {0, 1, 17, 30, 59, 60, 61, 90, 118, 119})
	{
		const double ty = t + (static_cast<double>(y) / H - 0.5) * readout;
		renderer.render(poseAt(ty), ty, gs);
		EXPECT_TRUE(rowsEqual(rs.colour, gs.colour, y)) << "row " << y;
		EXPECT_TRUE(rowsEqual(rs.depth, gs.depth, y)) << "row " << y;
		EXPECT_TRUE(rowsEqual(rs.objectIndex, gs.objectIndex, y)) << "row " << y;
		differsFromMid += !rowsEqual(rs.colour, mid.colour, y);
	}
	// The pan moves the image by several pixels between the first and the last row.
	EXPECT_GE(differsFromMid, 6);
}

TEST(RollingShutterRender, ZeroReadoutIsTheGlobalShutterRender)
{
	const auto scene = test::sceneFromString(panSceneIni(0.0));
	const sim::Renderer renderer(scene);
	const double t = scene.frameTime(9);
	const auto poseAt = [&](double ti) { return sim::Renderer::toIsometry(scene.trajectory.poseAt(ti)); };
	sim::RenderOutput rs, gs;
	renderer.renderRollingShutter(poseAt, t, 0.0, rs);
	renderer.render(poseAt(t), t, gs);
	EXPECT_EQ(cv::countNonZero(rs.colour.reshape(1) != gs.colour.reshape(1)), 0);
	EXPECT_EQ(cv::countNonZero(rs.depth != gs.depth), 0);
	EXPECT_THROW(renderer.renderRollingShutter(poseAt, t, -0.01, rs), std::invalid_argument);
}

TEST(RollingShutterRender, SimulatorFramesUseTheSceneReadout)
{
	const auto rsScene = test::sceneFromString(panSceneIni(0.03));
	const auto gsScene = test::sceneFromString(panSceneIni(0.0));
	sim::SimFrame a, b;
	sim::Simulator(rsScene, 1).frame(12, a);
	sim::Simulator(gsScene, 1).frame(12, b);
	// Same timestamp and ground-truth pose (the frame's middle row), different images.
	EXPECT_EQ(a.frame.timestamp, b.frame.timestamp);
	EXPECT_EQ((a.T_world_cam - b.T_world_cam).norm(), 0.0);
	EXPECT_GT(cv::countNonZero(a.render.depth != b.render.depth), 500);
}
