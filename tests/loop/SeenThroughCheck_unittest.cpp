/** \file SeenThroughCheck_unittest.cpp
 * countSeenThrough against hand-placed geometry: a target keyframe that measures a wall at a
 * known depth, and landmarks on the wall (agreeing), behind it (occluded: no evidence) and in
 * front of it (seen through), moved into the target's frame by a known transform.
 */
#include <gtest/gtest.h>
#include <keygrid/loop/SeenThroughCheck.h>

#include <cmath>

using namespace keygrid;

namespace
{
constexpr double kWall = 3.0;  // [m] depth the target measures everywhere
const sfm::PinholeIntrinsics K{500, 500, 320, 240};

/** A keyframe whose keypoints sit on a 20 px lattice, each measuring the wall. */
sfm::KeyFrame wallKeyFrame()
{
	sfm::KeyFrame kf;
	kf.features.camera.width = 640;
	kf.features.camera.height = 480;
	for (int v = 10; v < 480; v += 20)
		for (int u = 10; u < 640; u += 20)
		{
			kf.features.keypoints.emplace_back(static_cast<float>(u), static_cast<float>(v), 31.f, -1.f, 0.f, 0);
			kf.features.undistorted.emplace_back(static_cast<float>(u), static_cast<float>(v));
			kf.features.depth.push_back(static_cast<float>(kWall));
		}
	const int n = static_cast<int>(kf.features.size());
	kf.features.descriptors = cv::Mat::zeros(n, 32, CV_8U);
	for (int l = 0; l < kf.features.numLevels; l++) kf.features.levelScale.push_back(std::pow(1.2, l));
	kf.features.buildGrid();
	return kf;
}
}  // namespace

TEST(SeenThroughCheck, CountsLandmarksOnBehindAndInFrontOfTheMeasuredSurface)
{
	// The source keyframe observes landmarks at pixel lattice points, at three depths.
	sfm::SparseMap map;
	sfm::KeyFrame src = wallKeyFrame();
	const auto srcId = map.addKeyFrame(src).id;
	const auto& f = map.keyframe(srcId).features;
	// The landmarks are expressed in a "points" frame shifted by t from the target camera:
	// p_target = T_target_points * p_points.
	Eigen::Isometry3d T_target_points = Eigen::Isometry3d::Identity();
	T_target_points.translation() = Eigen::Vector3d(0.2, -0.1, 0.5);
	auto at = [&](int i, double depth)
	{
		const Eigen::Vector3d p_target((f.undistorted[i].x - K.cx) / K.fx * depth, (f.undistorted[i].y - K.cy) / K.fy * depth, depth);
		return Eigen::Vector3d(T_target_points.inverse() * p_target);
	};
	// 30 on the wall (within the 10 % + 5 cm tolerance), 12 well in front, 7 behind.
	int i = 0;
	for (int k = 0; k < 30; k++, i += 7) map.addLandmark(at(i, kWall * 1.05), srcId, i);
	for (int k = 0; k < 12; k++, i += 7) map.addLandmark(at(i, 1.5), srcId, i);
	for (int k = 0; k < 7; k++, i += 7) map.addLandmark(at(i, 4.5), srcId, i);

	const auto c = loop::countSeenThrough(map, {srcId}, T_target_points, wallKeyFrame(), K);
	EXPECT_EQ(c.agreeing, 30);
	EXPECT_EQ(c.seenThrough, 12);
	EXPECT_DOUBLE_EQ(c.ratio(), 12.0 / 42.0);

	// Out of the image or behind the camera: not counted. Moving the points 10 m sideways puts
	// every one of them outside the target's view.
	Eigen::Isometry3d away = T_target_points;
	away.translation().x() += 10.0;
	const auto none = loop::countSeenThrough(map, {srcId}, away, wallKeyFrame(), K);
	EXPECT_EQ(none.agreeing + none.seenThrough, 0);
	EXPECT_EQ(none.ratio(), 0.0);
}
