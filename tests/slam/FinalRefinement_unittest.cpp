#include <keygrid/slam/FinalRefinement.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace keygrid;
using mrpt::poses::CPose3D;

TEST(FinalRefinement, SeedsAreBothEndsOfEveryLoopNewestFirstThenTheNewestKeyFrame)
{
	sfm::SparseMap map;
	for (int i = 0; i < 5; i++) map.addKeyFrame(sfm::KeyFrame{});
	std::vector<loop::LoopClosureEvent> loops(2);
	loops[0].keyframe = 3;
	loops[0].loopKeyFrame = 0;
	loops[1].keyframe = 4;
	loops[1].loopKeyFrame = 1;
	EXPECT_EQ(slam::finalWindowSeeds(loops, map), (std::vector<sfm::KeyFrameId>{4, 1, 3, 0, 4}));
	EXPECT_EQ(slam::finalWindowSeeds({}, map), (std::vector<sfm::KeyFrameId>{4}));
}

TEST(FinalRefinement, DisplacementCountsTheCentreAndThePointAheadOfTheCamera)
{
	const std::map<sfm::KeyFrameId, CPose3D> before{{1, CPose3D()}, {2, CPose3D()}};
	// Keyframe 1 moves 2 cm sideways; keyframe 2 turns 0.01 rad about its y axis (pitch), which
	// moves the point 4 m ahead on its optical (z) axis by 2 x 4 x sin(0.005) m.
	const std::map<sfm::KeyFrameId, CPose3D> after{{1, CPose3D(0.02, 0, 0, 0, 0, 0)}, {2, CPose3D(0, 0, 0, 0, 0.01, 0)}};
	EXPECT_NEAR(slam::largestDisplacement(before, after, 4.0), 8 * std::sin(0.005), 1e-9);
	EXPECT_NEAR(slam::largestDisplacement(before, after, 0.0), 0.02, 1e-12);
	// Keyframes absent from `after` (erased) do not count.
	EXPECT_EQ(slam::largestDisplacement(before, {{7, CPose3D(1, 0, 0, 0, 0, 0)}}, 4.0), 0.0);
}

namespace
{
/** A map of 60 landmarks on a 3 m wide wall 4 m ahead, one keyframe observing them all. */
void fillWallMap(sfm::SparseMap& map, std::vector<sfm::LandmarkId>& ids)
{
	constexpr int n = 60;
	sfm::KeyFrame kf;
	kf.features.keypoints.resize(n);
	kf.features.undistorted.resize(n);
	kf.features.depth.assign(n, 4.f);
	kf.features.descriptors = cv::Mat(n, 32, CV_8U, cv::Scalar(0));
	kf.features.levelScale = {1.0};
	const auto k = map.addKeyFrame(kf).id;
	for (int i = 0; i < n; i++)
		ids.push_back(map.addLandmark({-1.5 + 0.3 * (i % 10), -1.0 + 0.4 * (i / 10), 4.0 + 0.1 * (i % 3)}, k, i));
}

/** A tracked frame at `truth` observing `ids` (pixels and depths exact). */
sfm::TrackedFrame frameSeeing(
	const sfm::SparseMap& map, const std::vector<sfm::LandmarkId>& ids, const CPose3D& truth, const sfm::PinholeIntrinsics& K)
{
	sfm::TrackedFrame f;
	f.tracked = true;
	for (const auto id : ids)
	{
		mrpt::math::TPoint3D pc;
		const auto& p = map.landmark(id).p_world;
		truth.inverseComposePoint(p.x(), p.y(), p.z(), pc.x, pc.y, pc.z);
		sfm::FrameObservation o;
		o.u = static_cast<float>(K.fx * pc.x / pc.z + K.cx);
		o.v = static_cast<float>(K.fy * pc.y / pc.z + K.cy);
		o.depth = static_cast<float>(pc.z);
		f.observedLandmarks.push_back(id);
		f.observations.push_back(o);
	}
	return f;
}
}  // namespace

TEST(FinalRefinement, FramesConvergeToTheirPoseThroughFusedLandmarksAndTooFewKeepNone)
{
	std::vector<sfm::LandmarkId> ids;
	sfm::SparseMap map;
	fillWallMap(map, ids);
	const sfm::PinholeIntrinsics K;
	const CPose3D truth(0.1, -0.05, 0.2, 0.03, -0.02, 0.01);
	// Frame 1 sees 16 landmarks, frame 2 15; all three matched ids[0], since fused into ids[1]
	// and moved to ids[0]'s place: ids[0]'s observations still count, through the survivor,
	// and ids[1]'s own observations are now outliers (30 cm off) that the rounds must drop.
	std::vector<sfm::TrackedFrame> frames(3, frameSeeing(map, ids, truth, K));
	for (std::size_t i = 1; i < 3; i++)
	{
		frames[i].observedLandmarks.resize(17 - i);
		frames[i].observations.resize(17 - i);
	}
	map.landmark(ids[1]).p_world = map.landmark(ids[0]).p_world;
	map.replaceLandmark(ids[0], ids[1]);
	const CPose3D start(0.12, -0.04, 0.17, 0.04, -0.02, 0.0);
	const core::Trajectory base(3, {0.0, start});
	// (One round cannot: it solves with every observation and only classifies afterwards.)
	for (const int rounds : {2, 4})
	{
		sfm::PoseOptimizerOptions pose;
		pose.rounds = rounds;
		const auto refined = slam::refineFramePoses(frames, base, map, K, pose, 15, [](const sfm::TrackedFrame&) { return true; });
		ASSERT_EQ(refined.size(), 3u);
		for (std::size_t i = 0; i < 2; i++)
		{
			ASSERT_TRUE(refined[i].has_value()) << "frame " << i << ", " << rounds << " rounds";
			// Exact pixels (to float rounding): the pose is recovered to well under a millimetre.
			EXPECT_LT((refined[i]->asVectorVal() - truth.asVectorVal()).norm(), 1e-4) << "frame " << i << ", " << rounds << " rounds";
		}
		EXPECT_FALSE(refined[2].has_value()) << "14 inliers, fewer than minInliers = 15";
	}
	// A frame `select` refuses keeps none.
	const auto none = slam::refineFramePoses(frames, base, map, K, {}, 15, [](const sfm::TrackedFrame&) { return false; });
	EXPECT_FALSE(none[0].has_value());
}

TEST(FinalRefinement, ScaleBetweenIsTheSimilarityScaleOfTheKeyFrameCentres)
{
	// after = a similarity of before (scale 1.07, a turn, a shift) plus keyframes in one map only.
	const CPose3D S(0.4, -0.2, 1.0, 0.3, 0.1, -0.2);
	std::map<sfm::KeyFrameId, CPose3D> before, after;
	const std::vector<Eigen::Vector3d> centres{{0, 0, 0}, {1, 0.2, 0}, {2, -0.5, 0.3}, {0.5, 1.5, -1}, {-1, 0.3, 2}};
	for (std::size_t i = 0; i < centres.size(); i++)
	{
		const auto& c = centres[i];
		before[i] = CPose3D(c.x(), c.y(), c.z(), 0.1 * static_cast<double>(i), 0, 0);
		mrpt::math::TPoint3D p;
		S.composePoint(1.07 * c.x(), 1.07 * c.y(), 1.07 * c.z(), p.x, p.y, p.z);
		after[i] = CPose3D(p.x, p.y, p.z, -0.2, 0.05 * static_cast<double>(i), 0);  // orientations do not count
	}
	before[10] = CPose3D(50, 0, 0, 0, 0, 0);
	after[11] = CPose3D(-50, 0, 0, 0, 0, 0);
	EXPECT_NEAR(slam::scaleBetween(before, after), 1.07, 1e-12);
	EXPECT_EQ(slam::scaleBetween({{0, CPose3D()}}, {{0, CPose3D(1, 0, 0, 0, 0, 0)}}), 1.0);
}

namespace
{
/** Fills `map` without depth: 4 keyframes 0.3 m apart along x, each seeing the 60 landmarks of a 3 m
 * wall 4 m ahead at their exact pixels. Then the landmarks are put 5 % farther from the first
 * keyframe and the other keyframes moved by a few cm, as a drifting map leaves them. */
void fillDriftedMonocularMap(sfm::SparseMap& map, const sfm::PinholeIntrinsics& K)
{
	std::vector<Eigen::Vector3d> wall;
	for (int i = 0; i < 60; i++) wall.emplace_back(-1.5 + 0.3 * (i % 10), -1.0 + 0.4 * (i / 10), 4.0 + 0.1 * (i % 3));
	std::vector<sfm::LandmarkId> ids;
	for (int k = 0; k < 4; k++)
	{
		const CPose3D T(0.3 * k, 0, 0, 0, 0, 0);
		sfm::KeyFrame kf;
		kf.T_world_cam = T;
		kf.features.keypoints.resize(wall.size());
		kf.features.undistorted.resize(wall.size());
		kf.features.depth.assign(wall.size(), 0.f);
		kf.features.descriptors = cv::Mat(static_cast<int>(wall.size()), 32, CV_8U, cv::Scalar(0));
		kf.features.levelScale = {1.0};
		for (std::size_t i = 0; i < wall.size(); i++)
		{
			mrpt::math::TPoint3D pc;
			T.inverseComposePoint(wall[i].x(), wall[i].y(), wall[i].z(), pc.x, pc.y, pc.z);
			kf.features.undistorted[i] = {static_cast<float>(K.fx * pc.x / pc.z + K.cx), static_cast<float>(K.fy * pc.y / pc.z + K.cy)};
			kf.features.keypoints[i].pt = kf.features.undistorted[i];
		}
		const auto id = map.addKeyFrame(std::move(kf)).id;
		for (std::size_t i = 0; i < wall.size(); i++)
		{
			if (k == 0)
				ids.push_back(map.addLandmark(1.05 * wall[i], id, static_cast<int>(i)));
			else
				map.addObservation(ids[i], id, static_cast<int>(i));
		}
		if (k > 0) map.keyframe(id).T_world_cam = CPose3D(0.3 * k + 0.02 * k, 0.01 * k, -0.03, 0.002 * k, 0, 0);
	}
	for (const auto id : ids) map.updateLandmarkStats(id);
	for (const auto& [id, kf] : map.keyframes()) map.updateCovisibility(id);
}

std::map<sfm::KeyFrameId, CPose3D> keyFramePoses(const sfm::SparseMap& map)
{
	std::map<sfm::KeyFrameId, CPose3D> out;
	for (const auto& [id, kf] : map.keyframes()) out[id] = kf.T_world_cam;
	return out;
}
}  // namespace

TEST(FinalRefinement, WithoutDepthTheFinalAdjustmentKeepsTheMapsScale)
{
	const sfm::PinholeIntrinsics K;
	slam::RefinementOptions rc;
	const sfm::LocalMapperOptions mapping;
	sfm::SparseMap free, held;
	fillDriftedMonocularMap(free, K);
	fillDriftedMonocularMap(held, K);
	const auto before = keyFramePoses(free);
	const auto rFree = slam::finalBundleAdjustment(free, K, {}, rc, mapping, false);
	const auto rHeld = slam::finalBundleAdjustment(held, K, {}, rc, mapping, true);
	// Left alone the adjustment rescales the map (the 5 % between landmarks and keyframes is
	// reconciled at a scale of its own); held, the keyframes' spread is what it was.
	const double sFree = slam::scaleBetween(before, keyFramePoses(free));
	EXPECT_GT(std::abs(sFree - 1.0), 1e-3);
	EXPECT_EQ(rFree.undoneScale, 1.0);
	EXPECT_NEAR(rHeld.undoneScale, sFree, 1e-6);
	EXPECT_NEAR(slam::scaleBetween(before, keyFramePoses(held)), 1.0, 1e-9);
	// The held map is the free one scaled about the origin (the fixed first keyframe), so
	// every reprojection is the same.
	for (const auto& [id, T] : keyFramePoses(held))
	{
		const auto& Tf = free.keyframe(id).T_world_cam;
		EXPECT_LT((T.translation() * sFree - Tf.translation()).norm(), 1e-6) << "keyframe " << id;
	}
	for (const auto& [id, lm] : held.landmarks()) EXPECT_LT((lm.p_world * sFree - free.landmark(id).p_world).norm(), 1e-6);
	EXPECT_EQ(rHeld.report.iterations, rFree.report.iterations);
}
