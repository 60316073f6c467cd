#include <keygrid/sfm/SparseMap.h>

#include "TestData.h"

using namespace keygrid::sfm;
using mrpt::poses::CPose3D;

namespace
{
KeyFrame makeKf(const CPose3D& pose, int nKps)
{
	KeyFrame kf;
	kf.T_world_cam = pose;
	kf.features.keypoints.resize(static_cast<std::size_t>(nKps));
	kf.features.undistorted.resize(static_cast<std::size_t>(nKps));
	kf.features.depth.assign(static_cast<std::size_t>(nKps), 1.f);
	kf.features.descriptors = cv::Mat(nKps, 32, CV_8U, cv::Scalar(0));
	kf.features.levelScale = {1.0, 1.2, 1.44};
	return kf;
}
}  // namespace

TEST(SparseMap, ObservationsCovisibilityAndErasure)
{
	SparseMap m;
	const auto a = m.addKeyFrame(makeKf(CPose3D(), 40)).id;
	const auto b = m.addKeyFrame(makeKf(CPose3D(0.1, 0, 0, 0, 0, 0), 40)).id;
	std::vector<LandmarkId> lms;
	for (int i = 0; i < 30; i++)
	{
		lms.push_back(m.addLandmark({0.1 * i, 0, 2}, a, i));
		if (i < 20) m.addObservation(lms.back(), b, i + 5);
	}
	m.updateCovisibility(b);
	EXPECT_EQ(m.keyframe(a).covisibility.at(b), 20);
	EXPECT_EQ(m.keyframe(b).covisibility.at(a), 20);
	EXPECT_EQ(m.bestCovisibles(a, 5), std::vector<KeyFrameId>{b});
	EXPECT_EQ(m.keyframe(b).trackedLandmarks(), 20);
	// Fusing a duplicate moves its observations.
	const auto dup = m.addLandmark({5, 5, 5}, b, 30);
	m.replaceLandmark(dup, lms[25]);
	EXPECT_FALSE(m.hasLandmark(dup));
	EXPECT_EQ(m.keyframe(b).landmarks[30], lms[25]);
	EXPECT_EQ(m.landmark(lms[25]).observations.size(), 2u);
	// Erasing a keyframe keeps landmarks seen elsewhere and drops the orphans.
	m.keyframe(b).parent = a;
	m.keyframe(b).hasParent = true;
	m.eraseKeyFrame(a);
	EXPECT_FALSE(m.hasKeyFrame(a));
	EXPECT_TRUE(m.hasLandmark(lms[0]));
	EXPECT_FALSE(m.hasLandmark(lms[29]));
}

TEST(SparseMap, ErasedKeyFramePosesFollowTheirParent)
{
	SparseMap m;
	const auto a = m.addKeyFrame(makeKf(CPose3D(1, 2, 3, 0.1, 0.2, 0.3), 1)).id;
	KeyFrame kb = makeKf(CPose3D(1.5, 2, 3, 0.2, 0.2, 0.3), 1);
	kb.parent = a;
	kb.hasParent = true;
	const auto b = m.addKeyFrame(std::move(kb)).id;
	const CPose3D T_a_b = m.keyframe(b).T_world_cam - m.keyframe(a).T_world_cam;
	m.eraseKeyFrame(b);
	// The parent moves (e.g. bundle adjustment): the erased child follows rigidly.
	m.keyframe(a).T_world_cam = CPose3D(0, 0, 0, 0, 0, 0);
	CPose3D T;
	ASSERT_TRUE(m.poseOf(b, T));
	EXPECT_NEAR((T.asVectorVal() - T_a_b.asVectorVal()).norm(), 0.0, 1e-12);
	EXPECT_FALSE(m.poseOf(99, T));
}

TEST(SparseMap, ResolveFollowsFusionsToTheSurvivingLandmark)
{
	SparseMap m;
	const auto a = m.addKeyFrame(makeKf(CPose3D(), 10)).id;
	const auto b = m.addKeyFrame(makeKf(CPose3D(0.1, 0, 0, 0, 0, 0), 10)).id;
	const auto l0 = m.addLandmark({0, 0, 2}, a, 0);
	const auto l1 = m.addLandmark({0, 0.01, 2}, b, 1);
	const auto l2 = m.addLandmark({0, 0.02, 2}, a, 2);
	EXPECT_EQ(m.resolve(l0), l0);
	m.replaceLandmark(l0, l1);  // l0 -> l1
	m.replaceLandmark(l1, l2);  // l1 -> l2, so l0 -> l2
	EXPECT_EQ(m.resolve(l0), l2);
	EXPECT_EQ(m.resolve(l1), l2);
	EXPECT_EQ(m.resolve(l2), l2);
	m.eraseLandmark(l2);
	EXPECT_EQ(m.resolve(l0), kNoLandmark);
	EXPECT_EQ(m.resolve(12345), kNoLandmark);
}

TEST(SparseMap, ResolvedLandmarksTableAgreesWithResolve)
{
	SparseMap m;
	const auto a = m.addKeyFrame(makeKf(CPose3D(), 10)).id;
	std::vector<LandmarkId> ids;
	for (int i = 0; i < 8; i++) ids.push_back(m.addLandmark({0.1 * i, 0, 2}, a, i));
	m.replaceLandmark(ids[0], ids[1]);
	m.replaceLandmark(ids[1], ids[5]);  // 0 -> 1 -> 5
	m.replaceLandmark(ids[2], ids[3]);
	m.eraseLandmark(ids[3]);  // 2 -> 3, erased
	m.eraseLandmark(ids[6]);
	const auto table = m.resolvedLandmarks();
	ASSERT_EQ(table.size(), ids.size());
	for (const LandmarkId id : ids) EXPECT_EQ(table[id], m.findLandmark(m.resolve(id))) << "landmark " << id;
	EXPECT_EQ(table[ids[0]], &m.landmark(ids[5]));
	EXPECT_EQ(table[ids[2]], nullptr);
	EXPECT_EQ(table[ids[6]], nullptr);
	EXPECT_EQ(table[ids[7]], &m.landmark(ids[7]));
}

TEST(SparseMap, RescaleScalesCentresPointsDistancesAndErasedRelativePoses)
{
	SparseMap m;
	const auto a = m.addKeyFrame(makeKf(CPose3D(0.5, -0.2, 1.0, 0.3, 0.1, -0.2), 10)).id;
	const auto b = m.addKeyFrame(makeKf(CPose3D(1.5, 0.4, 0.8, 0.5, 0, 0.1), 10)).id;
	auto kfC = makeKf(CPose3D(2.0, 0.1, 0.9, 0.6, 0.05, 0.1), 10);
	kfC.parent = b;
	kfC.hasParent = true;
	const auto c = m.addKeyFrame(kfC).id;
	const auto l = m.addLandmark({1, 2, 3}, a, 0);
	m.addObservation(l, b, 0);
	m.updateLandmarkStats(l);
	const auto before = m.landmark(l);
	m.eraseKeyFrame(c);
	const double s = 2.5;
	m.rescale(s);
	// x -> s x about the origin: centres and points times s, orientations unchanged.
	const CPose3D pa = m.keyframe(a).T_world_cam;
	EXPECT_NEAR(pa.x(), s * 0.5, 1e-12);
	EXPECT_NEAR(pa.y(), s * -0.2, 1e-12);
	EXPECT_NEAR(pa.z(), s * 1.0, 1e-12);
	EXPECT_NEAR(pa.yaw(), 0.3, 1e-12);
	EXPECT_NEAR((m.landmark(l).p_world - s * Eigen::Vector3d(1, 2, 3)).norm(), 0, 1e-12);
	EXPECT_NEAR(m.landmark(l).minDistance, s * before.minDistance, 1e-12);
	EXPECT_NEAR(m.landmark(l).maxDistance, s * before.maxDistance, 1e-12);
	// The erased keyframe follows its parent at the new scale: its centre is s times the old.
	CPose3D pc;
	ASSERT_TRUE(m.poseOf(c, pc));
	EXPECT_NEAR(pc.x(), s * 2.0, 1e-9);
	EXPECT_NEAR(pc.y(), s * 0.1, 1e-9);
	EXPECT_NEAR(pc.z(), s * 0.9, 1e-9);
	EXPECT_NEAR(pc.yaw(), 0.6, 1e-9);
	EXPECT_THROW(m.rescale(0), std::invalid_argument);
	EXPECT_THROW(m.rescale(-1), std::invalid_argument);
	EXPECT_THROW(m.rescale(std::nan("")), std::invalid_argument);
}
