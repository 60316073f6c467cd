/** RANSAC floor estimate on a synthetic scene whose desk top outnumbers the floor. */
#include <keygrid/maps/FloorPlaneEstimator.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace keygrid::maps;
using mrpt::math::TPoint3D;
using mrpt::math::TVector3D;

TEST(ISMFloorPlane, FindsLowestPlaneNotLargestOne)
{
	// World tilted by a known rotation (TUM-like, not gravity aligned).
	const mrpt::poses::CPose3D T_world_level(0.3, -0.2, 0.5, 0.4, 0.15, -0.1);
	std::mt19937 rng(3);
	std::uniform_real_distribution<double> U(-2.0, 2.0);
	std::normal_distribution<double> N(0.0, 0.004);
	std::vector<TPoint3D> pts;
	for (int i = 0; i < 1500; i++) pts.push_back(T_world_level.composePoint(TPoint3D(U(rng), U(rng), N(rng))));  // floor
	for (int i = 0; i < 4000; i++)  // desk top at 0.72 m: the largest plane
		pts.push_back(T_world_level.composePoint(TPoint3D(0.5 + 0.25 * U(rng), 0.25 * U(rng), 0.72 + N(rng))));
	for (int i = 0; i < 2000; i++)  // a wall
		pts.push_back(T_world_level.composePoint(TPoint3D(2.0 + N(rng), U(rng), 1.0 + 0.5 * U(rng))));
	const TPoint3D cam = T_world_level.composePoint(TPoint3D(0, 0, 1.4));
	// Up hint 12 degrees off the true up.
	const TVector3D trueUp = T_world_level.rotateVector(TVector3D(0, 0, 1));
	const TVector3D hint = T_world_level.rotateVector(TVector3D(std::sin(0.21), 0, std::cos(0.21)));

	FloorPlaneRansacOptions o;
	const auto plane = estimateFloorPlane(pts, hint, cam, o);
	ASSERT_TRUE(plane.has_value());
	const double cosAngle = plane->normal.x * trueUp.x + plane->normal.y * trueUp.y + plane->normal.z * trueUp.z;
	EXPECT_GT(cosAngle, std::cos(0.5 * M_PI / 180.0));
	EXPECT_NEAR(plane->height(cam), 1.4, 0.01);
	EXPECT_GE(plane->inliers, 1400u);

	const auto T_world_floor = floorPoseFromPlane(*plane, cam, T_world_level.rotateVector(TVector3D(1, 0, 0)));
	// In the estimated floor frame the camera is 1.4 m up and the desk 0.72 m up.
	EXPECT_NEAR(T_world_floor.inverseComposePoint(cam).z, 1.4, 0.01);
	EXPECT_NEAR(T_world_floor.inverseComposePoint(cam).x, 0.0, 1e-9);
	const TPoint3D desk = T_world_level.composePoint(TPoint3D(0.5, 0, 0.72));
	EXPECT_NEAR(T_world_floor.inverseComposePoint(desk).z, 0.72, 0.02);
}

TEST(ISMFloorPlane, NoPlaneBelowCameraGivesNullopt)
{
	std::vector<TPoint3D> pts;
	for (int i = 0; i < 50; i++)
		for (int j = 0; j < 50; j++) pts.emplace_back(i * 0.02, j * 0.02, 2.0);  // a ceiling
	EXPECT_FALSE(estimateFloorPlane(pts, TVector3D(0, 0, 1), TPoint3D(0.5, 0.5, 1.0), {}).has_value());
	FloorPlaneRansacOptions bad;
	bad.maxTiltDeg = 95;
	EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(ISMFloorPlane, FindsAFloorHoldingAFewPerCentOfThePoints)
{
	// A room seen from its middle: walls and a table top, the floor a 3 % strip. 300 fixed
	// hypotheses would draw three floor points with probability 1 - (1 - 0.03^3)^300 = 0.8 %;
	// the adaptive count (log 0.01 / log(1 - f^3) with f = minInlierFraction) finds it.
	std::mt19937 rng(5);
	std::uniform_real_distribution<double> U(0.0, 1.0);
	std::normal_distribution<double> N(0.0, 0.005);
	std::vector<TPoint3D> pts;
	for (int i = 0; i < 600; i++) pts.emplace_back(3.5 + 0.5 * U(rng), 4 * U(rng), N(rng));  // floor strip
	for (int i = 0; i < 5000; i++) pts.emplace_back(1 + U(rng), 1 + U(rng), 0.75 + N(rng));  // table top
	for (int i = 0; i < 14400; i++)  // two walls, floor to ceiling
	{
		const double t = 4 * U(rng), h = 2.6 * U(rng);
		pts.push_back(i % 2 ? TPoint3D(4.0 + N(rng), t, h) : TPoint3D(t, 4.0 + N(rng), h));
	}
	const TPoint3D cam(2, 2, 1.3);
	FloorPlaneRansacOptions o;
	o.minInlierFraction = 0.02;
	const auto plane = estimateFloorPlane(pts, TVector3D(0, 0, 1), cam, o);
	ASSERT_TRUE(plane.has_value());
	EXPECT_GT(plane->normal.z, std::cos(1.0 * M_PI / 180.0));
	// The refined plane also takes in the walls' lowest 2 cm, so it may sit up to 2 cm low; the
	// inlier range is an empirical margin.
	EXPECT_NEAR(plane->height(cam), 1.3, 0.02);
	EXPECT_GE(plane->inliers, 550u);
	EXPECT_LE(plane->inliers, 900u);
}
