/** \file SessionRecorder_unittest.cpp
 * The recorder writes what changed in a sparse map, keyframe by keyframe; whatever the map went
 * through (new keyframes, moved poses, landmarks created, fused, culled, re-observed, a keyframe
 * culled), loading the file gives the map back: the in-memory map is the ground truth.
 */
#include <keygrid/core/Frame.h>
#include <keygrid/slam/SessionLoader.h>
#include <keygrid/slam/SessionRecorder.h>
#include <keygrid/store/SparseMapRecords.h>

#include <filesystem>

#include "../store/StoreTestHelpers.h"
#include "../store/SyntheticSession.h"
#include "TestData.h"

using namespace keygrid;

namespace
{
/** A keyframe with features (no landmarks yet) and images. */
sfm::KeyFrame makeKeyFrame(sfm::KeyFrameId id)
{
	sfm::KeyFrame kf = store::toKeyFrame(test::syntheticKeyFrame(id, 120));
	kf.landmarks.assign(kf.features.size(), sfm::kNoLandmark);
	kf.colour = test::syntheticImage(id, true, 64, 48);
	kf.depth = core::depthRawToMetres(test::syntheticDepthRaw(id, 64, 48), kf.features.camera.depthUnits);
	return kf;
}

void expectSameMap(const sfm::SparseMap& a, const sfm::SparseMap& b)
{
	ASSERT_EQ(a.numKeyFrames(), b.numKeyFrames());
	ASSERT_EQ(a.numLandmarks(), b.numLandmarks());
	for (const auto& [id, ka] : a.keyframes())
	{
		SCOPED_TRACE("keyframe " + std::to_string(id));
		ASSERT_TRUE(b.hasKeyFrame(id));
		const auto& kb = b.keyframe(id);
		EXPECT_LT((ka.T_world_cam.asVectorVal() - kb.T_world_cam.asVectorVal()).norm(), 1e-12);
		EXPECT_EQ(ka.landmarks, kb.landmarks);
		EXPECT_EQ(ka.covisibility, kb.covisibility);
	}
	for (const auto& [id, la] : a.landmarks())
	{
		SCOPED_TRACE("landmark " + std::to_string(id));
		ASSERT_TRUE(b.hasLandmark(id));
		const auto& lb = b.landmark(id);
		EXPECT_EQ(la.p_world, lb.p_world);
		EXPECT_EQ(la.observations, lb.observations);
		EXPECT_EQ(la.visibleCount, lb.visibleCount);
		EXPECT_EQ(la.foundCount, lb.foundCount);
		EXPECT_EQ(la.hoc.counts(), lb.hoc.counts());
		EXPECT_TRUE(test::sameBits(la.descriptor, lb.descriptor));
	}
}

std::unique_ptr<sfm::SparseMap> load(const std::string& path)
{
	auto m = std::make_unique<sfm::SparseMap>();
	slam::loadSparseMap(store::SessionStore::Open(path), *m);
	return m;
}
}  // namespace

TEST(SessionRecorder, TheFileFollowsTheMapThroughEveryKindOfChange)
{
	const std::string dir = test::scratchDir("session_recorder");
	const std::string path = dir + "/map.kgmap";
	slam::SessionRecorderOptions opts;
	opts.snapshotEvery = 0;
	slam::SessionRecorder rec(path, opts);
	EXPECT_FALSE(std::filesystem::exists(path)) << "the file appears with the first keyframe";

	sfm::SparseMap map;
	// Keyframes 0 and 1 with landmarks seen by both.
	for (int k = 0; k < 2; k++) map.addKeyFrame(makeKeyFrame(0));
	for (int i = 0; i < 40; i++)
	{
		const auto lm = map.addLandmark(Eigen::Vector3d(0.1 * i, 1, 2), 0, i);
		map.addObservation(lm, 1, i + 1);
		map.updateLandmarkStats(lm);
	}
	map.updateCovisibility(0, 15);
	map.updateCovisibility(1, 15);
	rec.afterKeyFrame(map, nullptr, nullptr, nullptr);
	rec.flush();
	ASSERT_TRUE(std::filesystem::exists(path));
	expectSameMap(map, *load(path));

	// Local-BA-like changes: a pose and positions move; a landmark is culled, two are fused,
	// keyframe 2 arrives and re-observes old landmarks and adds its own.
	map.keyframe(1).T_world_cam = mrpt::poses::CPose3D(0.2, 0.1, 0, 0.05, 0, 0);
	map.landmark(3).p_world += Eigen::Vector3d(0.01, 0, 0);
	map.eraseLandmark(7);
	map.replaceLandmark(9, 8);
	map.addKeyFrame(makeKeyFrame(2));
	for (int i = 20; i < 40; i++) map.addObservation(static_cast<sfm::LandmarkId>(i), 2, i + 50);
	for (int i = 0; i < 10; i++) map.addLandmark(Eigen::Vector3d(-1, 0.1 * i, 3), 2, i);
	map.landmark(21).visibleCount += 5;
	map.landmark(21).hoc.add(3, 1, 20, 60);
	for (sfm::KeyFrameId k = 0; k < 3; k++) map.updateCovisibility(k, 15);
	rec.afterKeyFrame(map, nullptr, nullptr, nullptr);

	// Keyframe 1 is culled (its observations go; landmarks left unobserved go too).
	map.eraseKeyFrame(1);
	for (const sfm::KeyFrameId k : {sfm::KeyFrameId(0), sfm::KeyFrameId(2)}) map.updateCovisibility(k, 15);
	map.landmark(30).foundCount += 2;
	rec.finish(map, nullptr, nullptr);

	expectSameMap(map, *load(path));
	const auto store = store::SessionStore::Open(path);
	for (const auto& r : store.loadKeyFrames())
		EXPECT_EQ(r.landmarks, map.keyframe(r.id).landmarks) << "the stored association of keyframe " << r.id << " was kept up to date";
	EXPECT_EQ(store.counts().keyframesWithImages, 2u);
	const auto img = store.loadImages(2);
	EXPECT_TRUE(test::sameBits(img.colour, map.keyframe(2).colour));
	EXPECT_EQ(rec.stats().updates, 2u);
	EXPECT_THROW(slam::SessionRecorder(path, opts), std::runtime_error) << "an existing file is not overwritten";
}

TEST(SessionRecorder, BetweenUpdatesOnlyLandmarkCountersMayLag)
{
	// A run killed between two updates: the file holds the map as of the last update, except
	// that visibility counters and HOC bins changed by tracking alone wait for the landmark's
	// next structural change or the end of the run.
	const std::string path = test::scratchDir("session_recorder_lag") + "/map.kgmap";
	slam::SessionRecorder rec(path, {});
	sfm::SparseMap map;
	map.addKeyFrame(makeKeyFrame(0));
	const auto a = map.addLandmark(Eigen::Vector3d(1, 2, 3), 0, 4);
	const auto b = map.addLandmark(Eigen::Vector3d(1, 2, 4), 0, 5);
	rec.afterKeyFrame(map, nullptr, nullptr, nullptr);
	map.landmark(a).visibleCount = 9;
	map.landmark(b).visibleCount = 7;
	map.landmark(b).p_world.z() = 4.5;
	rec.afterKeyFrame(map, nullptr, nullptr, nullptr);
	rec.flush();
	{
		const auto mid = load(path);
		EXPECT_EQ(mid->landmark(a).visibleCount, 1) << "counters alone are not written per keyframe";
		EXPECT_EQ(mid->landmark(b).visibleCount, 7) << "written with the landmark's move";
		EXPECT_EQ(mid->landmark(b).p_world.z(), 4.5);
	}
	rec.finish(map, nullptr, nullptr);
	EXPECT_EQ(load(path)->landmark(a).visibleCount, 9) << "all of them at the end";
}
