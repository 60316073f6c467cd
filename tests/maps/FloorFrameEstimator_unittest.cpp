// The run's floor frame: the lowest large horizontal plane under the cameras, on a
// synthetic room where the floor holds 2 % of the depth samples and a table and a sofa top are
// larger planes (the floor is seen as a strip at the foot of a wall, behind them).
#include <keygrid/maps/FloorFrameEstimator.h>
#include <keygrid/maps/FloorPlaneEstimator.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/math/geometry.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "CameraPoses.h"

using namespace keygrid::maps;
using mrpt::math::TPoint3D;
using mrpt::math::TPoint3Df;
using mrpt::math::TVector3D;
using mrpt::poses::CPose3D;

namespace
{
/** The room in its level frame L (z up, floor z = 0, 6 x 5 m, walls 2.5 m high at x = 0, 6,
 * y = 0, 5). Its world is a SLAM world: the first camera's optical frame. */
struct Room
{
	/** Pose of the level frame in the world: the inverse of the first camera's pose in L. */
	CPose3D T_world_level;
	/** Keyframe camera poses in the world (optical frames). */
	std::vector<CPose3D> T_world_cams;
	/** Per keyframe, its depth samples in its camera frame. */
	std::vector<std::vector<TPoint3Df>> samples_cam;
};

/** An optical camera at `eye` (level frame) looking at `at`. */
CPose3D lookAt(const TPoint3D& eye, const TPoint3D& at)
{
	const TVector3D f = TVector3D(at.x - eye.x, at.y - eye.y, at.z - eye.z) * (1.0 / (at - eye).norm());
	TVector3D x = mrpt::math::crossProduct3D(f, TVector3D(0, 0, 1));
	x *= 1.0 / x.norm();
	return keygrid::test::opticalPose(x, mrpt::math::crossProduct3D(f, x), f, eye);
}

/** 10 keyframes at 1.3 m, looking 20 deg down towards the wall x = 6 (a hand-held camera),
 * and per keyframe 2000 samples (level frame) with sigma = 5 mm noise along z: 2 % floor (a
 * 0.3 m strip at the foot of the wall), 15 % table top (0.75 m, 1.6 x 1.2 m), 10 % sofa seat
 * (0.45 m, 2 x 0.8 m), the rest on the walls x = 6 and y = 0, y = 5. */
Room makeRoom()
{
	Room room;
	std::vector<CPose3D> T_level_cams;
	for (int k = 0; k < 10; k++)
	{
		const TPoint3D eye(2.0 + 0.05 * k, 1.8 + 0.15 * k, 1.3);
		const TPoint3D at(6.0, 1.5 + 0.25 * k, 1.3 - std::tan(20.0 * M_PI / 180) * (6.0 - eye.x));
		T_level_cams.push_back(lookAt(eye, at));
	}
	room.T_world_level = -T_level_cams.front();
	std::mt19937 rng(7);
	std::uniform_real_distribution<double> U(0, 1);
	std::normal_distribution<double> noise(0, 0.005);
	for (const auto& T_level_cam : T_level_cams)
	{
		std::vector<TPoint3Df> s;
		for (int i = 0; i < 2000; i++)
		{
			const double r = U(rng);
			TPoint3D p;
			if (r < 0.02) p = {5.7 + 0.3 * U(rng), 0.2 + 4.6 * U(rng), 0.0};
			else if (r < 0.17) p = {3.6 + 1.6 * U(rng), 1.5 + 1.2 * U(rng), 0.75};
			else if (r < 0.27) p = {3.8 + 2.0 * U(rng), 3.9 + 0.8 * U(rng), 0.45};
			else if (r < 0.75) p = {6.0, 5.0 * U(rng), 2.5 * U(rng)};
			else if (r < 0.87) p = {3.0 + 3.0 * U(rng), 0.0, 2.5 * U(rng)};
			else p = {3.0 + 3.0 * U(rng), 5.0, 2.5 * U(rng)};
			p.z += noise(rng);
			const TPoint3D c = T_level_cam.inverseComposePoint(p);
			s.emplace_back(static_cast<float>(c.x), static_cast<float>(c.y), static_cast<float>(c.z));
		}
		room.samples_cam.push_back(std::move(s));
		room.T_world_cams.push_back(room.T_world_level + T_level_cam);
	}
	return room;
}

/** Height offset [m] (at the level frame's point `at`) and tilt [deg] of an estimated floor
 * frame against the room's true floor. */
std::pair<double, double> floorError(const CPose3D& T_world_floor, const Room& room, const TPoint3D& at)
{
	const CPose3D T_level_floor = -room.T_world_level + T_world_floor;
	const auto R = T_level_floor.getRotationMatrix();
	const double tilt = std::acos(std::min(1.0, R(2, 2))) * 180.0 / M_PI;
	// z of the estimated plane above `at`: plane n . (p - o) = 0 in the level frame.
	const double nx = R(0, 2), ny = R(1, 2), nz = R(2, 2);
	const double z = T_level_floor.z() - (nx * (at.x - T_level_floor.x()) + ny * (at.y - T_level_floor.y())) / nz;
	return {z, tilt};
}

/** Every keyframe of `room`, in order, added to `est`. */
void addRoomKeyframes(FloorFrameEstimator& est, const Room& room)
{
	for (std::size_t k = 0; k < room.T_world_cams.size(); k++) est.addKeyframe(k, room.T_world_cams[k], room.samples_cam[k]);
}
}  // namespace

TEST(FloorFrameEstimator, FindsAFloorOf2PercentUnderLargerTableAndSofaTops)
{
	const Room room = makeRoom();
	FloorFrameEstimator est;
	addRoomKeyframes(est, room);
	ASSERT_TRUE(est.T_world_floor());
	ASSERT_FALSE(est.history().empty());
	// The first keyframes see the floor beyond the table: from the third on, it is found
	// and later estimates stay within min_change / min_change_deg of it.
	EXPECT_LE(est.history().back().keyframes, 10u);
	EXPECT_TRUE(est.history().back().clearBelow);
	EXPECT_EQ(est.history().back().walls, 3u);
	// Within 2 cm / 1 deg under every camera and at the far corner of the room.
	for (const auto& T : room.T_world_cams)
	{
		const TPoint3D c = (-room.T_world_level + T).translation();
		const auto [dz, tilt] = floorError(*est.T_world_floor(), room, TPoint3D(c.x, c.y, 0));
		EXPECT_LT(std::abs(dz), 0.02);
		EXPECT_LT(tilt, 1.0);
	}
	const auto [dz, tilt] = floorError(*est.T_world_floor(), room, TPoint3D(0, 0, 0));
	EXPECT_LT(std::abs(dz), 0.02);
	EXPECT_LT(tilt, 1.0);
	// The frame: z up, the first camera 1.3 m above its origin, x along its heading.
	const auto cam0 = est.T_world_floor()->inverseComposePoint(room.T_world_cams[0].translation());
	EXPECT_NEAR(cam0.z, 1.3, 0.02);
	EXPECT_NEAR(cam0.x, 0.0, 1e-6);
	EXPECT_NEAR(cam0.y, 0.0, 1e-6);
}

TEST(FloorFrameEstimator, TheLargestLowPlaneOfTheOldSequentialRansacIsNotTheFloorHere)
{
	// The same samples through estimateFloorPlane (the ISM grid's standalone estimator, which
	// takes the lowest of the largest planes): on this room the estimate is not the floor,
	// which is what the lowest-plane search with the "points below" test fixes.
	const Room room = makeRoom();
	std::vector<TPoint3D> pts;
	TVector3D up(0, 0, 0);
	for (std::size_t k = 0; k < room.samples_cam.size(); k++)
	{
		for (const auto& p : room.samples_cam[k]) pts.push_back(room.T_world_cams[k].composePoint(TPoint3D(p.x, p.y, p.z)));
		up = up + room.T_world_cams[k].rotateVector(TVector3D(0, -1, 0));
	}
	const auto plane = estimateFloorPlane(pts, up, room.T_world_cams[0].translation(), FloorPlaneRansacOptions());
	ASSERT_TRUE(plane);
	const auto T = floorPoseFromPlane(*plane, room.T_world_cams[0].translation(), TVector3D(1, 0, 0));
	EXPECT_GT(std::abs(floorError(T, room, TPoint3D(3, 2.5, 0)).first), 0.3);
}

// With a generous max_below_share (as a monocular map needs: it keeps stray points under its
// floor) a desk top over a small visible floor has few enough points below to pass as clear, and
// holds far more than the floor: the points under it form a large plane of their own, so that
// lower plane is the floor. Stray points scattered under the floor form none and change nothing.
TEST(FloorFrameEstimator, AGenerousBelowShareStillTakesTheFloorUnderADeskTop)
{
	for (const bool strays : {false, true})
	{
		SCOPED_TRACE(strays ? "with stray points under the floor" : "floor, desk, walls");
		std::mt19937 rng(11);
		std::uniform_real_distribution<double> U(0, 1);
		std::normal_distribution<double> noise(0, 0.005);
		// Level frame, floor z = 0: 3 % floor, 25 % desk top at 0.75 m, 2 % strays 0.15-1 m under
		// the floor (or wall), the rest a wall above the desk.
		std::vector<TPoint3D> pts;
		for (int i = 0; i < 10000; i++)
		{
			const double r = U(rng);
			TPoint3D p;
			if (r < 0.03) p = {4.0 + 2.0 * U(rng), 5.0 * U(rng), 0.0};
			else if (r < 0.28) p = {1.0 + 2.5 * U(rng), 1.0 + 3.0 * U(rng), 0.75};
			else if (r < 0.30 && strays) p = {6.0 * U(rng), 5.0 * U(rng), -0.15 - 0.85 * U(rng)};
			else p = {6.0, 5.0 * U(rng), 0.9 + 1.6 * U(rng)};
			p.z += noise(rng);
			pts.push_back(p);
		}
		std::vector<TPoint3D> cams;
		for (int k = 0; k < 10; k++) cams.emplace_back(0.5 + 0.1 * k, 2.5, 1.3);
		FloorFrameOptions o;
		o.minSupport = 0.02;
		o.maxBelowShare = 3;
		o.searchUnderTheWinner = true;
		const auto fit = estimateLowestFloorPlane(pts, TVector3D(0, 0, 1), cams, o);
		ASSERT_TRUE(fit.has_value());
		EXPECT_NEAR(fit->plane.height(TPoint3D(2, 2, 0)), 0.0, 0.02);
		EXPECT_NEAR(fit->plane.height(TPoint3D(5, 2, 0)), 0.0, 0.02);
		EXPECT_TRUE(fit->clearBelow);
	}
}

TEST(FloorFrameEstimator, FollowsCorrectedPosesAndKeepsTheGivenFrame)
{
	const Room room = makeRoom();
	FloorFrameEstimator est;
	addRoomKeyframes(est, room);
	ASSERT_TRUE(est.T_world_floor());
	// The whole trajectory re-anchored by G: the floor frame follows, G * T_world_floor.
	const CPose3D G(0.3, -0.2, 0.1, 0.4, -0.1, 0.2);
	std::map<uint64_t, CPose3D> moved;
	for (std::size_t k = 0; k < room.samples_cam.size(); k++) moved[k] = G + room.T_world_cams[k];
	const CPose3D expected = G + *est.T_world_floor();
	EXPECT_TRUE(est.updatePoses(moved));
	// (Up to the RANSAC's inlier sets at the band edges, which round-off may change.)
	const CPose3D d = -expected + *est.T_world_floor();
	EXPECT_LT(d.translation().norm(), 1e-3);
	EXPECT_LT(std::abs(d.yaw()) + std::abs(d.pitch()) + std::abs(d.roll()), 1e-3);

	FloorFrameOptions o;
	o.givenPose = "[1 2 3 10 20 30]";
	FloorFrameEstimator given(o);
	ASSERT_TRUE(given.T_world_floor());
	EXPECT_TRUE(given.given());
	EXPECT_FALSE(given.addKeyframe(0, room.T_world_cams[0], room.samples_cam[0]));
	EXPECT_NEAR(given.T_world_floor()->yaw(), 10 * M_PI / 180, 1e-9);
	EXPECT_NEAR(given.T_world_floor()->z(), 3.0, 1e-12);
	EXPECT_TRUE(given.history().empty());
	EXPECT_NE(given.toJson().find("\"source\": \"given\""), std::string::npos);
}

TEST(FloorFrameEstimator, ReservoirIsBoundedAndScheduleIsPeriodic)
{
	const Room room = makeRoom();
	FloorFrameOptions o;
	o.reservoirSize = 5000;
	o.initialKeyframes = 3;
	o.reestimateEvery = 4;
	FloorFrameEstimator est(o);
	for (std::size_t k = 0; k < 30; k++) est.addKeyframe(k, room.T_world_cams[k % 10], room.samples_cam[k % 10]);
	EXPECT_EQ(est.samples(), 5000u);
	EXPECT_EQ(est.keyframes(), 30u);
	// Keyframes 1, 2, 3, then 7, 11, ..., 27: 3 + 6 estimates.
	EXPECT_EQ(est.estimates(), 9u);
}

TEST(FloorFrameEstimator, OptionsRoundTripAndNameTheBadKey)
{
	FloorFrameOptions a;
	a.givenPose = "[0.1 0.2 0.3 1 2 3]";
	a.upHint = TVector3D(0, -1, 0.1);
	a.reservoirSize = 1234;
	a.parallelPlanes = false;
	mrpt::config::CConfigFileMemory saved;
	a.saveToConfigFile(saved, "floor");
	const mrpt::config::CConfigFileMemory ini(saved.getContent());
	FloorFrameOptions b;
	b.loadFromConfigFile(ini, "floor");
	EXPECT_EQ(b.givenPose, a.givenPose);
	EXPECT_NEAR(b.upHint.z, 0.1, 1e-12);
	EXPECT_EQ(b.reservoirSize, 1234);
	EXPECT_FALSE(b.parallelPlanes);
	for (const auto& [key, value] : std::vector<std::pair<std::string, std::string>>{
			 {"min_support", "0"}, {"T_world_floor", "[1 2]"}, {"up_hint", "0 1"}, {"max_depth", "0.1"}})
	{
		mrpt::config::CConfigFileMemory bad;
		bad.write("floor", key, value);
		try
		{
			FloorFrameOptions c;
			c.loadFromConfigFile(bad, "floor");
			ADD_FAILURE() << key << " = " << value << " accepted";
		}
		catch (const std::invalid_argument& e)
		{
			EXPECT_NE(std::string(e.what()).find("[floor] " + key), std::string::npos) << e.what();
		}
	}
}
