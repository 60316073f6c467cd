#include <keygrid/sfm/BundleWindow.h>

#include <gtest/gtest.h>

using namespace keygrid::sfm;
using mrpt::poses::CPose3D;

namespace
{
/** Ten keyframes in a chain: keyframe i shares 20 + i landmarks with keyframe i + 1 and none
 * with any other, so every covisibility edge joins neighbours and the later edge weighs more. */
void buildChain(SparseMap& m)
{
	std::vector<KeyFrameId> ids;
	for (int i = 0; i < 10; i++)
	{
		KeyFrame kf;
		kf.T_world_cam = CPose3D(0.1 * i, 0, 0, 0, 0, 0);
		kf.features.keypoints.resize(100);
		kf.features.depth.assign(100, 1.f);
		kf.features.undistorted.resize(100);
		kf.features.descriptors = cv::Mat(100, 32, CV_8U, cv::Scalar(0));
		kf.features.levelScale = {1.0};
		ids.push_back(m.addKeyFrame(std::move(kf)).id);
	}
	for (int i = 0; i + 1 < 10; i++)
		for (int k = 0; k < 20 + i; k++)
		{
			// Keypoints 50.. of keyframe i see what keypoints 0.. of keyframe i + 1 see.
			const auto l = m.addLandmark({0.1 * i, 0.01 * k, 2}, ids[i], 50 + k);
			m.addObservation(l, ids[i + 1], k);
		}
	for (KeyFrameId id : ids) m.updateCovisibility(id);
}
}  // namespace

TEST(BundleWindow, GrowsRingByRingByCovisibilityWeight)
{
	SparseMap m;
	buildChain(m);
	ASSERT_EQ(m.keyframe(5).covisibility.at(6), 25);
	ASSERT_EQ(m.keyframe(5).covisibility.at(4), 24);
	// Ring 1 of 5: 6 (25 shared) before 4 (24); ring 2: 7 reached from 6, then 3 from 4.
	const auto w = growBundleWindow(m, {5}, 5);
	EXPECT_EQ(w.local, (std::vector<KeyFrameId>{5, 6, 4, 7, 3}));
	// The keyframes just outside see the landmarks of 3 and 7.
	EXPECT_EQ(w.fixed, (std::set<KeyFrameId>{2, 8}));
}

TEST(BundleWindow, SeedsOfSeveralLoopsShareTheBound)
{
	SparseMap m;
	buildChain(m);
	// Two seeds (e.g. the ends of a loop), a culled keyframe and a repeated seed: both seeds
	// first, then ring 1 in seed order (8 from 9; 2 before 0 from 1) until the bound.
	const auto w = growBundleWindow(m, {9, 1, 42, 9}, 4);
	EXPECT_EQ(w.local, (std::vector<KeyFrameId>{9, 1, 8, 2}));
	EXPECT_EQ(w.fixed, (std::set<KeyFrameId>{0, 3, 7}));
}

TEST(BundleWindow, ABoundAboveTheMapTakesEveryKeyFrameWithNothingFixed)
{
	SparseMap m;
	buildChain(m);
	const auto w = growBundleWindow(m, {3}, 100);
	EXPECT_EQ(w.local.size(), 10u);
	EXPECT_TRUE(w.fixed.empty());
	EXPECT_THROW(growBundleWindow(m, {3}, 0), std::invalid_argument);
	EXPECT_TRUE(growBundleWindow(m, {42}, 5).local.empty());
}
