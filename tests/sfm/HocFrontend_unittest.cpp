// HocFrontend: the per-frame HOC update of the tracker: matched +1, visible-unmatched -1,
// occluded untouched, pruning, selection; histograms seeded from the creating keyframe; the
// residual gate on recovered matches; the confirmation of the initial map.
#include <keygrid/sfm/HocFrontend.h>

#include "TestData.h"

using namespace keygrid::sfm;
using mrpt::poses::CPose3D;

namespace
{
KeyFrame makeKf(int nKps)
{
	KeyFrame kf;
	kf.features.keypoints.resize(static_cast<std::size_t>(nKps));
	kf.features.undistorted.resize(static_cast<std::size_t>(nKps));
	kf.features.depth.assign(static_cast<std::size_t>(nKps), 2.f);
	kf.features.descriptors = cv::Mat(nKps, 32, CV_8U, cv::Scalar(0));
	kf.features.levelScale = {1.0};
	kf.features.camera.width = 640;
	kf.features.camera.height = 480;
	return kf;
}
ProjectedLandmark projected(LandmarkId id, float u, float v, float depth)
{
	ProjectedLandmark p;
	p.id = id;
	p.p_world.setZero();
	p.u = u;
	p.v = v;
	p.depth = depth;
	return p;
}
}  // namespace

TEST(HocFrontend, MatchedUpVisibleDownOccludedUntouchedVanishedPruned)
{
	keygrid::maps::HocOptions o;  // weight(n) = sigmoid(n)
	o.enabled = true;
	o.pruneThreshold = 0.6;  // prune when max n <= 0
	o.selectThreshold = 0.2;  // usable while n >= -1
	o.decrementNeedsKeypoint = false;  // the paper's rule: every visible miss counts
	const HocFrontend hoc(o);
	SparseMap map;
	const auto kf = map.addKeyFrame(makeKf(4)).id;  // camera at the origin
	// Four landmarks 2 m in front of the camera (off the optical axis, which meets an
	// icosahedron edge), each seen once by the keyframe (+1 seed), all in the same bin.
	std::vector<LandmarkId> lm;
	for (int i = 0; i < 4; i++) lm.push_back(map.addLandmark({0.3 + 0.01 * i, 0.2, 2.0}, kf, i));
	FrameFeatures f = makeKf(4).features;
	const std::vector<LandmarkId> matched{lm[0], kNoLandmark, kNoLandmark, kNoLandmark};
	// lm1: the depth image sees a surface 1 m in front of it (occluded); lm2: sees through it
	// (wall at 3 m); lm3: no depth reading there (nothing closer measured -> not occluded).
	cv::Mat depth(480, 640, CV_32F, cv::Scalar(3.0f));
	depth.at<float>(100, 100) = 1.0f;
	depth.at<float>(300, 300) = 0.0f;
	const std::vector<ProjectedLandmark> visible{projected(lm[1], 100, 100, 2.0f), projected(lm[2], 200, 200, 2.0f), projected(lm[3], 300, 300, 2.0f)};
	const Eigen::Vector3d c(0, 0, 0);
	const int b = hoc.geometry().bin(map.landmark(lm[0]).p_world, c);
	for (LandmarkId l : lm) ASSERT_EQ(hoc.geometry().bin(map.landmark(l).p_world, c), b);
	const auto st = hoc.update(map, f, matched, visible, {}, depth, c, 4.f, MatcherOptions());
	EXPECT_EQ(st.incremented, 1);
	EXPECT_EQ(st.occluded, 1);
	EXPECT_EQ(st.decremented, 2);
	// lm2 and lm3 went from +1 to 0: max weight 0.5 < 0.6 -> pruned; lm0 has +2, lm1 kept +1.
	EXPECT_EQ(st.pruned, 2);
	ASSERT_TRUE(map.hasLandmark(lm[0]));
	ASSERT_TRUE(map.hasLandmark(lm[1]));
	EXPECT_FALSE(map.hasLandmark(lm[2]));
	EXPECT_FALSE(map.hasLandmark(lm[3]));
	EXPECT_EQ(map.landmark(lm[0]).hoc.count(b), 2);
	EXPECT_EQ(map.landmark(lm[1]).hoc.count(b), 1);
	// Selection: usable while weight > 0.2, i.e. n >= -1 in the camera's bin.
	auto& l1 = map.landmark(lm[1]);
	EXPECT_TRUE(hoc.usable(l1, map, c));
	l1.hoc.add(b, -2, o.countLimit, hoc.geometry().numBins());  // n = -1
	EXPECT_TRUE(hoc.usable(l1, map, c));
	l1.hoc.add(b, -1, o.countLimit, hoc.geometry().numBins());  // n = -2
	EXPECT_FALSE(hoc.usable(l1, map, c));
	// From another bin (camera 3 m to the side and behind) the point is still usable.
	EXPECT_TRUE(hoc.usable(l1, map, Eigen::Vector3d(3, 0, 4)));
}

TEST(HocFrontend, OcclusionToleranceGrowsWithDepth)
{
	keygrid::maps::HocOptions o;
	o.occlusionToleranceAbs = 0.05;
	o.occlusionToleranceRel = 0.03;
	const HocFrontend hoc(o);
	cv::Mat depth(10, 10, CV_32F, cv::Scalar(2.0f));
	// predicted 2.1 m: tolerance 0.05 + 0.063 = 0.113 -> 2.0 is not in front by more than that
	EXPECT_FALSE(hoc.occluded(depth, 5, 5, 2.1f));
	// predicted 2.2 m: tolerance 0.116 < 0.2 -> occluded
	EXPECT_TRUE(hoc.occluded(depth, 5, 5, 2.2f));
	depth.at<float>(5, 5) = 0;
	EXPECT_FALSE(hoc.occluded(depth, 5, 5, 2.2f));
	EXPECT_FALSE(hoc.occluded(depth, 50, 5, 2.2f));  // outside the image
}

TEST(HocFrontend, MissCountsOnlyWithKeypointInSearchWindowWhenRequired)
{
	// Three landmarks in view, none matched, their surfaces measured at the predicted depth:
	//  lm0: a keypoint 1 px away at the predicted level (searched, did not match) -> -1;
	//  lm1: the nearest keypoint 10 px away, outside the 4 px window -> nothing detected there;
	//  lm2: a keypoint at its pixel but 3 levels above the predicted one (outside level +-1).
	// The standard rule decrements (and prunes) all three; with decrement_needs_keypoint only lm0.
	for (const bool needKeypoint : {false, true})
	{
		SCOPED_TRACE(needKeypoint ? "decrement_needs_keypoint" : "every miss");
		keygrid::maps::HocOptions o;
		o.enabled = true;
		o.pruneThreshold = 0.6;  // prune when max n <= 0
		o.decrementNeedsKeypoint = needKeypoint;
		const HocFrontend hoc(o);
		SparseMap map;
		const auto kf = map.addKeyFrame(makeKf(3)).id;
		std::vector<LandmarkId> lm;
		for (int i = 0; i < 3; i++) lm.push_back(map.addLandmark({0.3 + 0.01 * i, 0.2, 2.0}, kf, i));
		FrameFeatures f = makeKf(3).features;
		f.levelScale = {1.0, 1.2, 1.44, 1.728};
		f.undistorted = {{201.f, 200.f}, {410.f, 300.f}, {300.f, 100.f}};
		for (std::size_t i = 0; i < 3; i++) f.keypoints[i] = cv::KeyPoint(f.undistorted[i], 31.f, -1, 0, i == 2 ? 3 : 0);
		f.buildGrid();
		std::vector<ProjectedLandmark> visible{projected(lm[0], 200, 200, 2.0f), projected(lm[1], 400, 300, 2.0f), projected(lm[2], 300, 100, 2.0f)};
		EXPECT_TRUE(HocFrontend::keypointInWindow(f, visible[0], 4.f));
		EXPECT_FALSE(HocFrontend::keypointInWindow(f, visible[1], 4.f));
		EXPECT_FALSE(HocFrontend::keypointInWindow(f, visible[2], 4.f));
		EXPECT_TRUE(HocFrontend::keypointInWindow(f, visible[1], 12.f));  // 10 px away
		const cv::Mat depth(480, 640, CV_32F, cv::Scalar(2.0f));
		const Eigen::Vector3d c(0, 0, 0);
		const int b = hoc.geometry().bin(map.landmark(lm[0]).p_world, c);
		const auto st = hoc.update(map, f, std::vector<LandmarkId>(3, kNoLandmark), visible, {}, depth, c, 4.f, MatcherOptions());
		EXPECT_EQ(st.incremented, 0);
		EXPECT_EQ(st.occluded, 0);
		EXPECT_EQ(st.decremented, needKeypoint ? 1 : 3);
		EXPECT_EQ(st.undetected, needKeypoint ? 2 : 0);
		EXPECT_EQ(st.seenThrough, 0);  // the depth image reads every surface where predicted
		EXPECT_EQ(st.pruned, needKeypoint ? 1 : 3);  // +1 seed - 1 = 0: max weight 0.5 < 0.6
		EXPECT_FALSE(map.hasLandmark(lm[0]));
		for (int i : {1, 2})
		{
			ASSERT_EQ(map.hasLandmark(lm[i]), needKeypoint);
			if (needKeypoint)
			{
				EXPECT_EQ(map.landmark(lm[i]).hoc.count(b), 1);
			}
		}
	}
}

TEST(HocFrontend, SeedCountsOnlyTheCreatingKeyframe)
{
	// A point created by keyframe A (camera at the origin) that local mapping later also
	// associates with keyframe B (camera 3 m to the side, another bin): the seed puts
	// initial_count in A's bin only. If A is culled before the point is first used, the point
	// starts unconfirmed (n = 0 everywhere).
	keygrid::maps::HocOptions o;
	o.initialCount = 1;
	const HocFrontend hoc(o);
	for (const bool cullA : {false, true})
	{
		SCOPED_TRACE(cullA ? "creating keyframe culled" : "creating keyframe kept");
		SparseMap map;
		const auto a = map.addKeyFrame(makeKf(2)).id;
		KeyFrame kfB = makeKf(2);
		kfB.T_world_cam = CPose3D(3, 0, 0, 0, 0, 0);
		const auto b = map.addKeyFrame(kfB).id;
		const LandmarkId id = map.addLandmark({0.3, 0.2, 2.0}, a, 0);
		map.addObservation(id, b, 1);
		const Eigen::Vector3d p = map.landmark(id).p_world;
		const int binA = hoc.geometry().bin(p, Eigen::Vector3d(0, 0, 0));
		const int binB = hoc.geometry().bin(p, Eigen::Vector3d(3, 0, 0));
		ASSERT_NE(binA, binB);
		if (cullA) map.eraseKeyFrame(a);
		ASSERT_TRUE(map.hasLandmark(id));
		auto& lm = map.landmark(id);
		hoc.seed(lm, map);
		EXPECT_EQ(lm.hoc.count(binA), cullA ? 0 : 1);
		EXPECT_EQ(lm.hoc.count(binB), 0);
		EXPECT_EQ(lm.hoc.maxCount(), cullA ? 0 : 1);
	}
}

TEST(HocFrontend, RecoveredMatchMustFitThePoseLikeAnInlier)
{
	// Three excluded landmarks, all within the 4 px search window of a keypoint with the same
	// descriptor (level 0, sigma 1 px; bf = 40, disparity sigma 0.25 px):
	//  lm0: keypoint 1 px off, same depth: chi2 = 1 <= 7.815 -> recovered (+1);
	//  lm1: keypoint 3.5 px off (a walker's point that moved): chi2 = 12.25 -> a miss (-1);
	//  lm2: keypoint on the projection but measured at 2.0 m where 1.87 m is predicted (the
	//       surface behind, so not occluded): disparity residual (20 - 21.39) / 0.25 = -5.56 px,
	//       chi2 = 30.9 -> a miss (-1).
	keygrid::maps::HocOptions o;
	o.enabled = true;
	o.pruneThreshold = 0.1;  // keep everything: this test is about the counts
	HocFrontend hoc(o);
	hoc.setResidualGate(PoseOptimizerOptions());
	SparseMap map;
	const auto kf = map.addKeyFrame(makeKf(3)).id;
	std::vector<LandmarkId> lm;
	for (int i = 0; i < 3; i++) lm.push_back(map.addLandmark({0.3 + 0.01 * i, 0.2, 2.0}, kf, i));
	FrameFeatures f = makeKf(3).features;
	f.undistorted = {{201.f, 200.f}, {303.5f, 200.f}, {400.f, 200.f}};
	for (std::size_t i = 0; i < 3; i++) f.keypoints[i] = cv::KeyPoint(f.undistorted[i], 31.f, -1, 0, 0);
	f.buildGrid();
	std::vector<ProjectedLandmark> excluded{projected(lm[0], 200, 200, 2.0f), projected(lm[1], 300, 200, 2.0f), projected(lm[2], 400, 200, 1.87f)};
	for (std::size_t i = 0; i < 3; i++) excluded[i].descriptor = &map.landmark(lm[i]).descriptor;
	EXPECT_TRUE(hoc.fitsPose(f, 0, excluded[0]));
	EXPECT_FALSE(hoc.fitsPose(f, 1, excluded[1]));
	EXPECT_FALSE(hoc.fitsPose(f, 2, excluded[2]));
	const cv::Mat depth(480, 640, CV_32F, cv::Scalar(2.0f));
	const Eigen::Vector3d c(0, 0, 0);
	const auto st = hoc.update(map, f, std::vector<LandmarkId>(3, kNoLandmark), {}, excluded, depth, c, 4.f, MatcherOptions());
	EXPECT_EQ(st.recovered, 1);
	EXPECT_EQ(st.incremented, 1);
	EXPECT_EQ(st.decremented, 2);
	const int b = hoc.geometry().bin(map.landmark(lm[0]).p_world, c);
	EXPECT_EQ(map.landmark(lm[0]).hoc.count(b), 2);  // seed 1 + recovered
	EXPECT_EQ(map.landmark(lm[1]).hoc.count(b), 0);  // seed 1 - miss
	EXPECT_EQ(map.landmark(lm[2]).hoc.count(b), 0);
}

TEST(HocFrontend, InitialMapIsConfirmedOnceAndPassesTheDefaultSelection)
{
	// With the defaults (initial_count 1, select_threshold 0.8 = sigmoid(n) > 0.8, n >= 2) a
	// new point is not used until one match confirms it; the initialization keyframe's points
	// get that confirmation up front (n = 2) so the second frame has something to track.
	const keygrid::maps::HocOptions o;
	ASSERT_EQ(o.initialCount, 1);
	ASSERT_LT(o.weight(1), o.selectThreshold);
	ASSERT_GT(o.weight(2), o.selectThreshold);
	const HocFrontend hoc(o);
	SparseMap map;
	const auto kf0 = map.addKeyFrame(makeKf(2)).id;
	const LandmarkId a = map.addLandmark({0.3, 0.2, 2.0}, kf0, 0), b = map.addLandmark({-0.3, 0.1, 2.5}, kf0, 1);
	const auto kf1 = map.addKeyFrame(makeKf(1)).id;
	const LandmarkId later = map.addLandmark({0.1, -0.2, 1.5}, kf1, 0);
	hoc.confirmInitialMap(map, kf0);
	const Eigen::Vector3d c(0, 0, 0);
	for (LandmarkId id : {a, b})
	{
		auto& lm = map.landmark(id);
		EXPECT_EQ(lm.hoc.count(hoc.geometry().bin(lm.p_world, c)), 2);
		EXPECT_TRUE(hoc.usable(lm, map, c));
	}
	auto& l = map.landmark(later);
	EXPECT_FALSE(hoc.usable(l, map, c));  // seeded to 1 on first use, not confirmed
	EXPECT_EQ(l.hoc.count(hoc.geometry().bin(l.p_world, c)), 1);
}

TEST(HocFrontend, SeenThroughNeedsFarDepthAllAroundTheProjection)
{
	// Predicted 2 m, tolerance 0.05 + 0.03 * 2 = 0.11 m.
	const HocFrontend hoc{keygrid::maps::HocOptions()};
	cv::Mat depth(100, 100, CV_32F, cv::Scalar(3.0f));
	EXPECT_TRUE(hoc.seenThrough(depth, 50, 50, 2.0f));    // a wall 1 m behind: the point is gone
	EXPECT_FALSE(hoc.seenThrough(depth, 50, 50, 2.95f));  // within the tolerance: still there
	// A depth edge 2 px to the right of the projection: the near side is the point's surface.
	depth.colRange(52, 100).setTo(2.0f);
	EXPECT_FALSE(hoc.seenThrough(depth, 50, 50, 2.0f));
	EXPECT_TRUE(hoc.seenThrough(depth, 45, 50, 2.0f));  // 7 px from the edge, all samples far
	depth.at<float>(47, 42) = 0.0f;                    // a hole at one of the samples
	EXPECT_FALSE(hoc.seenThrough(depth, 45, 50, 2.0f));
	EXPECT_FALSE(hoc.seenThrough(depth, 1, 50, 2.0f));  // samples outside the image
}

TEST(HocFrontend, SeenThroughMissCountsWithoutKeypoint)
{
	// decrement_needs_keypoint: a miss with no keypoint in the window is not counted, unless
	// the depth image reads the background all around the projection (the object vanished).
	keygrid::maps::HocOptions o;
	o.enabled = true;
	ASSERT_TRUE(o.decrementNeedsKeypoint);
	const HocFrontend hoc(o);
	SparseMap map;
	const auto kf = map.addKeyFrame(makeKf(2)).id;
	const LandmarkId gone = map.addLandmark({0.3, 0.2, 2.0}, kf, 0), there = map.addLandmark({0.31, 0.2, 2.0}, kf, 1);
	FrameFeatures f = makeKf(1).features;
	f.undistorted = {{600.f, 400.f}};  // far from both projections
	f.keypoints[0] = cv::KeyPoint(f.undistorted[0], 31.f, -1, 0, 0);
	f.buildGrid();
	cv::Mat depth(480, 640, CV_32F, cv::Scalar(2.0f));
	depth(cv::Rect(180, 180, 40, 40)).setTo(4.0f);  // background seen where `gone` was
	const std::vector<ProjectedLandmark> visible{projected(gone, 200, 200, 2.0f), projected(there, 300, 200, 2.0f)};
	const Eigen::Vector3d c(0, 0, 0);
	const auto st = hoc.update(map, f, {kNoLandmark}, visible, {}, depth, c, 4.f, MatcherOptions());
	EXPECT_EQ(st.decremented, 1);
	EXPECT_EQ(st.undetected, 1);
	EXPECT_EQ(st.seenThrough, 1);
	EXPECT_EQ(st.pruned, 1);  // seed 1 - 1 = 0: weight 0.5 < prune threshold 0.6
	EXPECT_FALSE(map.hasLandmark(gone));
	EXPECT_TRUE(map.hasLandmark(there));
}

TEST(HocFrontend, FallbackSelectionAdmitsUnconfirmedButNotContradictedPoints)
{
	const keygrid::maps::HocOptions o;  // select 0.8 (n >= 2); fallback p(n) > p(0): n >= 1
	const HocFrontend hoc(o);
	ASSERT_TRUE(hoc.hasFallback());
	SparseMap map;
	const auto kf = map.addKeyFrame(makeKf(1)).id;
	auto& lm = map.landmark(map.addLandmark({0.3, 0.2, 2.0}, kf, 0));
	const Eigen::Vector3d c(0, 0, 0);
	const int b = hoc.geometry().bin(lm.p_world, c);
	EXPECT_FALSE(hoc.usable(lm, map, c));       // n = 1 after the seed
	EXPECT_TRUE(hoc.usable(lm, map, c, true));
	lm.hoc.add(b, -1, o.countLimit, hoc.geometry().numBins());  // n = 0: as many misses as matches
	EXPECT_FALSE(hoc.usable(lm, map, c, true));
	keygrid::maps::HocOptions loose;
	loose.selectThreshold = 0.1;
	EXPECT_FALSE(HocFrontend(loose).hasFallback());  // the normal selection is already looser
}
