// The Tracker's monocular mode (Tracker_monocular.cpp) on synthetic features without depth
// (SyntheticFeatures.h): a random point cloud in front of the first camera, observed from
// ground-truth poses. The map starts from two views once the parallax suffices, at the scale
// that puts the first keyframe's median scene depth at 1; later frames are tracked on its
// landmarks, and their poses equal the ground truth up to that one scale. A camera that only
// turns never starts a map.
#include <keygrid/sfm/Tracker.h>

#include "SyntheticFeatures.h"

#include <gtest/gtest.h>

#include <algorithm>

using namespace keygrid;
using mrpt::poses::CPose3D;

namespace tracker_monocular_unittest
{
namespace
{
constexpr int kWorldPoints = 600;

/** Points spread over the first camera's image at depths in [2, 5] m. */
test::SyntheticPoints makeWorld(const core::RgbdCamera& cam, std::mt19937& rng)
{
	return test::pointsInView(cam, rng, kWorldPoints, 10, 2.0, 5.0);
}

/** An image-only frame and its features (no depth anywhere). */
struct MonoFrame
{
	core::Frame frame;
	sfm::FrameFeatures features;
};

MonoFrame observe(const test::SyntheticPoints& world, int i, const CPose3D& T_world_cam, const core::RgbdCamera& cam, std::mt19937& rng)
{
	MonoFrame m;
	m.frame = test::blankFrame(static_cast<std::size_t>(i), cam);
	m.frame.depth.release();
	m.features = test::observePoints(world, T_world_cam, cam, {}, rng);
	std::fill(m.features.depth.begin(), m.features.depth.end(), 0.f);
	return m;
}

sfm::TrackerOptions monocularOptions()
{
	sfm::TrackerOptions o;
	o.monocular = true;
	return o;
}

/** Sideways path: 2 cm a frame along x with a slight turn (about 0.3 deg of parallax a frame). */
CPose3D sidewaysPose(int i)
{
	const double s = static_cast<double>(i);
	return CPose3D(0.02 * s, 0.002 * s, 0.004 * s, 0.002 * s, 0.001 * s, 0.0);
}

double medianLandmarkDepth(const sfm::SparseMap& map, sfm::KeyFrameId kf)
{
	std::vector<double> z;
	const auto T_cam_world = -map.keyframe(kf).T_world_cam;
	for (auto l : map.keyframe(kf).landmarks)
		if (l != sfm::kNoLandmark && map.hasLandmark(l))
		{
			const auto& p = map.landmark(l).p_world;
			double x, y, zc;
			T_cam_world.composePoint(p.x(), p.y(), p.z(), x, y, zc);
			z.push_back(zc);
		}
	std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(z.size() / 2), z.end());
	return z[z.size() / 2];
}
}  // namespace

TEST(TrackerMonocular, StartsFromTwoViewsAtMedianDepthOneAndTracksUpToThatScale)
{
	const core::RgbdCamera cam;
	std::mt19937 rng(7);
	const auto world = makeWorld(cam, rng);
	sfm::SparseMap map;
	sfm::Tracker tracker(map, monocularOptions());
	std::optional<int> startFrame;
	double scale = 0;  // metres per map unit
	for (int i = 0; i < 20; i++)
	{
		const CPose3D T_gt = sidewaysPose(i);
		auto m = observe(world, i, T_gt, cam, rng);
		const auto tf = tracker.track(m.frame, std::move(m.features));
		if (!startFrame)
		{
			if (!tf.tracked)
			{
				EXPECT_EQ(tracker.state(), sfm::TrackingState::NotInitialized);
				EXPECT_FALSE(tf.initMessage.empty()) << "frame " << i;
				EXPECT_EQ(tf.initNewReference, i == 0) << tf.initMessage;
				continue;
			}
			startFrame = i;
			ASSERT_EQ(tf.method, sfm::TrackingMethod::Init);
			ASSERT_TRUE(tf.hasInitialKeyFrame);
			EXPECT_EQ(tf.initialFrameIndex, 0u);
			ASSERT_EQ(map.numKeyFrames(), 2u);
			EXPECT_TRUE(tf.newKeyFrame);
			// The reference camera is the world frame; the first keyframe's median depth is 1.
			const auto& kf1 = map.keyframe(tf.initialKeyFrame);
			EXPECT_LT(kf1.T_world_cam.translation().norm(), 1e-12);
			EXPECT_LT(test::rotationAngleDeg(kf1.T_world_cam), 1e-9);
			EXPECT_NEAR(medianLandmarkDepth(map, tf.initialKeyFrame), 1.0, 1e-9);
			EXPECT_GE(map.numLandmarks(), 500u);
			scale = T_gt.translation().norm() / tf.T_world_cam.translation().norm();
			// The scale in metres per map unit is the median true depth of the landmarks.
			EXPECT_GT(scale, 2.0);
			EXPECT_LT(scale, 5.0);
		}
		ASSERT_TRUE(tf.tracked) << "frame " << i;
		// Exact measurements: the pose is the ground truth's up to the map's scale (float
		// keypoints: 1e-7 relative, well below the bound).
		const CPose3D T_est = tf.T_world_cam;
		const Eigen::Vector3d t_est = scale * Eigen::Vector3d(T_est.x(), T_est.y(), T_est.z());
		const Eigen::Vector3d t_gt(T_gt.x(), T_gt.y(), T_gt.z());
		EXPECT_LT((t_est - t_gt).norm(), 1e-4) << "frame " << i;
		CPose3D rotationError = T_est - T_gt;
		EXPECT_LT(test::rotationAngleDeg(rotationError), 1e-3) << "frame " << i;
	}
	ASSERT_TRUE(startFrame.has_value());
	// 1 deg of median parallax (TwoViewOptions::minParallaxDeg) takes 3 to 5 frames here.
	EXPECT_LE(*startFrame, 8);
}

TEST(TrackerMonocular, AKeyFrameComesWhenTrackingFallsBelowTheMonocularShare)
{
	const core::RgbdCamera cam;
	std::mt19937 rng(8);
	const auto world = makeWorld(cam, rng);
	sfm::SparseMap map;
	const auto opts = monocularOptions();
	sfm::Tracker tracker(map, opts);
	sfm::KeyFrameId ref = 0;
	int refTracked = 0;
	bool sawKeyFrame = false;
	for (int i = 0; i < 60 && !sawKeyFrame; i++)
	{
		auto m = observe(world, i, sidewaysPose(i), cam, rng);
		const auto tf = tracker.track(m.frame, std::move(m.features));
		if (tf.method == sfm::TrackingMethod::Init)
		{
			ref = tf.keyframe;
			// With two keyframes every landmark is seen by both: all count.
			refTracked = map.keyframe(ref).trackedLandmarks(2, &map);
			continue;
		}
		if (!tf.tracked) continue;
		// ORB-SLAM2's monocular rule: a keyframe exactly when the inliers fall below 0.9 x
		// the reference keyframe's landmarks (no timeout within these frames).
		const bool weak = tf.inliers < opts.mono.keyFrameTrackedRatio * refTracked;
		EXPECT_EQ(tf.newKeyFrame, weak) << "frame " << i << ": " << tf.inliers << " inliers, reference " << refTracked;
		sawKeyFrame = tf.newKeyFrame;
	}
	EXPECT_TRUE(sawKeyFrame);
	// A keyframe of a camera without depth brings no landmark of its own.
	std::size_t own = 0;
	for (const auto& [id, lm] : map.landmarks()) own += lm.firstKeyFrame != ref && lm.firstKeyFrame != ref - 1;
	EXPECT_EQ(own, 0u);
}

TEST(TrackerMonocular, APureRotationNeverStartsAMapAndTheReferenceIsRenewed)
{
	const core::RgbdCamera cam;
	std::mt19937 rng(9);
	const auto world = makeWorld(cam, rng);
	sfm::SparseMap map;
	auto opts = monocularOptions();
	opts.mono.initMaxFrames = 8;
	sfm::Tracker tracker(map, opts);
	for (int i = 0; i < 20; i++)
	{
		// Turning on the spot by 0.3 deg a frame: no translation, no parallax.
		auto m = observe(world, i, CPose3D(0, 0, 0, 0.005 * i, 0.003 * i, 0), cam, rng);
		const auto tf = tracker.track(m.frame, std::move(m.features));
		ASSERT_FALSE(tf.tracked) << "frame " << i;
		EXPECT_EQ(tf.initNewReference, i % 8 == 0) << "frame " << i << ": " << tf.initMessage;
		if (i % 8 != 0) { EXPECT_NE(tf.initMessage.find("parallax"), std::string::npos) << tf.initMessage; }
	}
	EXPECT_EQ(map.numKeyFrames(), 0u);
	EXPECT_EQ(tracker.state(), sfm::TrackingState::NotInitialized);
}

// A plane in view (a wall): the homography's two motions both keep every point in front of
// the cameras, and the two-view initializer refuses them as ambiguous at any parallax. The
// true motion's plane is the same from every current frame, the other one turns with the
// direction of travel: on a curved path a later frame picks the true motion, and the map is
// the ground truth's up to its scale. With the two-view rival rule on (the default,
// TwoViewOptions::rivalParallaxShare) the plane's second, rotation-like motion is no rival and
// the true map starts without an ambiguous frame; the plane rule is tested with it off.
TEST(TrackerMonocular, AWallInViewIsResolvedByThePlaneAndStartsTheTrueMap)
{
	for (const bool rivalRule : {false, true})
	{
		SCOPED_TRACE(rivalRule ? "rival rule" : "plane rule");
		const core::RgbdCamera cam;
		std::mt19937 rng(10);
		// A wall 3 m ahead, tilted 20 deg about the vertical, filling the first image.
		test::SyntheticPoints wall;
		std::uniform_real_distribution<double> x(-2.5, 2.5), y(-1.8, 1.8);
		for (int i = 0; i < kWorldPoints; i++)
		{
			const double u = x(rng);
			wall.p_world.emplace_back(u * std::cos(0.35), y(rng), 3.0 + u * std::sin(0.35));
		}
		wall.descriptors = test::randomDescriptors(kWorldPoints, rng);
		// A curved path: the direction of travel turns by about 2 deg a frame.
		const auto pose = [](int i) {
			const double s = static_cast<double>(i), a = 0.035 * s;
			return CPose3D(0.6 * std::sin(a), 0.001 * s, 0.6 * (1 - std::cos(a)), -0.5 * a, 0.0, 0.0);
		};
		sfm::SparseMap map;
		auto opts = monocularOptions();
		opts.mono.initPlaneNormalDeg = 1.5;
		if (!rivalRule) opts.mono.twoView.rivalParallaxShare = 0;
		sfm::Tracker tracker(map, opts);
		std::optional<int> startFrame;
		bool sawAmbiguous = false;
		double scale = 0;
		for (int i = 0; i < 40; i++)
		{
			const CPose3D T_gt = pose(i);
			auto m = observe(wall, i, T_gt, cam, rng);
			const auto tf = tracker.track(m.frame, std::move(m.features));
			if (!startFrame && !tf.tracked)
			{
				sawAmbiguous |= tf.initMessage.find("ambiguous") != std::string::npos;
				continue;
			}
			if (!startFrame)
			{
				startFrame = i;
				ASSERT_EQ(tf.method, sfm::TrackingMethod::Init);
				const bool byPlane = tf.initMessage.find("the plane of the first ambiguous frame picked the motion") != std::string::npos;
				EXPECT_EQ(byPlane, !rivalRule) << tf.initMessage;
				scale = T_gt.translation().norm() / tf.T_world_cam.translation().norm();
			}
			ASSERT_TRUE(tf.tracked) << "frame " << i;
			const CPose3D T_est = tf.T_world_cam;
			const Eigen::Vector3d t_est = scale * Eigen::Vector3d(T_est.x(), T_est.y(), T_est.z());
			const Eigen::Vector3d t_gt(T_gt.x(), T_gt.y(), T_gt.z());
			// Exact measurements: the true motion up to the map's scale (the other motion of the
			// plane would be off by the whole baseline).
			EXPECT_LT((t_est - t_gt).norm(), 1e-3) << "frame " << i;
			EXPECT_LT(test::rotationAngleDeg(T_est - T_gt), 1e-2) << "frame " << i;
		}
		EXPECT_EQ(sawAmbiguous, !rivalRule);
		ASSERT_TRUE(startFrame.has_value());
	}
}
}  // namespace tracker_monocular_unittest
