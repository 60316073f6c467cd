// HocFrontend: the per-frame HOC update of the tracker: matched +1, visible-unmatched -1,
// occluded untouched, pruning, selection; histograms seeded from keyframe observations.
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
