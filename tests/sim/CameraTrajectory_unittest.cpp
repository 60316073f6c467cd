// Camera paths: waypoints reached on time, smooth, loops closed, look-at respected; every
// shipped scene loads and moves slowly enough for a visual frontend.
#include <keygrid/sim/CameraTrajectory.h>
#include <keygrid/sim/Scene.h>
#include <mrpt/system/filesystem.h>

#include "SimTestScenes.h"
#include "TestData.h"

#include <cmath>
#include <iostream>

using namespace keygrid;

namespace
{
std::vector<sim::Waypoint> square()
{
	std::vector<sim::Waypoint> w(4);
	const double p[4][2] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}};
	for (int i = 0; i < 4; i++)
	{
		w[i].eye = Eigen::Vector3d(p[i][0], p[i][1], 1.2);
		w[i].target = Eigen::Vector3d(1, 1, 0.8);  // all look at the middle
	}
	return w;
}

Eigen::Vector3d eyeOf(const mrpt::poses::CPose3D& p) { return {p.x(), p.y(), p.z()}; }
}  // namespace

TEST(CameraTrajectory, ClosedLoopPassesWaypointsAndReturnsToStart)
{
	sim::CameraTrajectoryOptions o;
	o.loop = true;
	const sim::CameraTrajectory tr(square(), 20.0, o);
	// Equal sides and turns: the four segments last 5 s each.
	ASSERT_EQ(tr.knotTimes().size(), 5u);
	for (int i = 0; i < 4; i++)
	{
		EXPECT_NEAR(tr.knotTimes()[i], 5.0 * i, 1e-9);
		EXPECT_NEAR((eyeOf(tr.poseAt(5.0 * i)) - square()[i].eye).norm(), 0.0, 1e-12);
	}
	const mrpt::poses::CPose3D a = tr.poseAt(0), b = tr.poseAt(20.0);
	EXPECT_NEAR((a - b).translation().norm(), 0.0, 1e-12);
	EXPECT_NEAR((a.getRotationMatrix() - b.getRotationMatrix()).norm(), 0.0, 1e-12);
	// Velocity is continuous through a waypoint (C1 Hermite): compare one-sided differences.
	const double h = 1e-5;
	const Eigen::Vector3d vIn = (eyeOf(tr.poseAt(5.0)) - eyeOf(tr.poseAt(5.0 - h))) / h;
	const Eigen::Vector3d vOut = (eyeOf(tr.poseAt(5.0 + h)) - eyeOf(tr.poseAt(5.0))) / h;
	EXPECT_NEAR((vIn - vOut).norm(), 0.0, 1e-3);
	EXPECT_GT(vIn.norm(), 0.1);
}

TEST(CameraTrajectory, OpticalAxisPointsAtTheTargetWithZUp)
{
	const sim::CameraTrajectory tr(square(), 10.0);
	for (double t : {0.0, 1.7, 4.2, 10.0})
	{
		const sim::Waypoint w = tr.waypointAt(t);
		const mrpt::poses::CPose3D p = tr.poseAt(t);
		const auto& R = p.getRotationMatrix();
		const Eigen::Vector3d z(R(0, 2), R(1, 2), R(2, 2)), x(R(0, 0), R(1, 0), R(2, 0)),
			y(R(0, 1), R(1, 1), R(2, 1));
		EXPECT_NEAR((z - (w.target - w.eye).normalized()).norm(), 0.0, 1e-12);
		EXPECT_NEAR(x.z(), 0.0, 1e-12);  // no roll: image x stays horizontal
		EXPECT_LT(y.z(), 0.0);           // image y points down
		EXPECT_NEAR(R.det(), 1.0, 1e-12);
	}
	// An open path starts and ends at rest on its first and last waypoints.
	EXPECT_NEAR((eyeOf(tr.poseAt(10.0)) - square()[3].eye).norm(), 0.0, 1e-12);
	EXPECT_NEAR((eyeOf(tr.poseAt(1e-4)) - square()[0].eye).norm(), 0.0, 1e-6);
}

TEST(CameraTrajectory, BadWaypointsAreRejected)
{
	const std::string base =
		"[scene]\nframes = 10\n[object.q]\ntype = quad\ncorner = 0 0 0\nedge1 = 1 0 0\nedge2 = 0 1 "
		"0\n";
	EXPECT_THROW(
		test::sceneFromString(base + "[trajectory]\nwp_00 = 0 0 1 0 0 1\n"), std::invalid_argument);
	EXPECT_THROW(
		test::sceneFromString(base + "[trajectory]\nwp_00 = 0 0 1 0 0 5\n"), std::invalid_argument);
	EXPECT_THROW(
		test::sceneFromString(base + "[trajectory]\nwp_00 = 0 0 1 x 0 5\n"), std::invalid_argument);
	EXPECT_THROW(
		test::sceneFromString(base + "[trajectory]\nloop = true\n"), std::invalid_argument);
	// yaw/pitch form: yaw 90 deg looks along +y.
	const sim::Scene s = test::sceneFromString(base + "[trajectory]\nwp_00 = 0 0 1 90 0\n");
	const mrpt::math::CMatrixDouble33 R = s.cameraPose(0).getRotationMatrix();
	EXPECT_NEAR(R(1, 2), 1.0, 1e-12);
}

TEST(ShippedScenes, LoadAndMoveWithinTrackableSpeeds)
{
	const std::string dir = test::sourceDir() + "/config/sim";
	// Generated in about a minute at most (1200 frames); room_survey (the 2D grid's accuracy
	// benchmark) walks the whole room and office_loop (the long loop of the loop-closing batch)
	// 44 m, each in about four; tests use neither at full length.
	const struct
	{
		const char* name;
		unsigned maxFrames;
	} scenes[] = {{"room_loop", 1200}, {"corridor_loop", 1200}, {"static_camera_dynamic", 1200},
				  {"static_camera_crowd", 1200}, {"moving_camera_dynamic", 1200}, {"relocalization", 1200},
				  {"room_survey", 1950}, {"office_loop", 3300}};
	for (const auto& [n, maxFrames] : scenes)
	{
		const std::string path = dir + "/" + n + ".ini";
		ASSERT_TRUE(mrpt::system::fileExists(path)) << path;
		const sim::Scene s = sim::Scene::loadFromFile(path);
		EXPECT_EQ(s.options.name, n);
		EXPECT_EQ(s.camera.width, 640u);
		EXPECT_EQ(s.camera.height, 480u);
		EXPECT_EQ(s.options.rateHz, 30.0);
		double v = 0, w = 0;
		s.trajectory.maxSpeeds(s.options.rateHz, v, w);
		std::cout << n << ": " << s.options.frames << " frames, max " << v << " m/s, "
				  << w * 180 / M_PI << " deg/s\n";
		EXPECT_LE(v, 0.5) << n;
		EXPECT_LE(w * 180 / M_PI, 60.0) << n;
		EXPECT_LE(s.options.frames, maxFrames) << n;
		// Loops return to the start: first and (virtual) next-after-last frame coincide.
		if (s.trajectory.options().loop)
		{
			const auto d = s.cameraPose(0) - s.trajectory.poseAt(s.trajectory.duration());
			EXPECT_NEAR(d.translation().norm(), 0.0, 1e-9) << n;
		}
	}
}
