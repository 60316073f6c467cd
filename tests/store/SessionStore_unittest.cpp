/** \file SessionStore_unittest.cpp
 * Round trips of every record type (bit-exact), upserts and erasures, and the errors Open()
 * gives for a file of another schema version, a damaged file and a file that is not a session.
 */
#include <keygrid/store/KeyFrameImageCodec.h>
#include <keygrid/store/MapSnapshotCodec.h>
#include <keygrid/store/SessionStore.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <sqlite3.h>

#include <filesystem>
#include <fstream>

#include "StoreTestHelpers.h"
#include "SyntheticSession.h"
#include "TestData.h"

using namespace keygrid;
using namespace keygrid::store;
using keygrid::test::expectSameKeyFrame;
using keygrid::test::expectSameLandmark;
using keygrid::test::sameBits;

namespace
{
SessionMeta testMeta()
{
	SessionMeta m;
	m.camera = core::RgbdCamera::Preset("fr1");
	m.vocabulary = {"keygrid_orb_k10_L4.bin", "0123456789abcdef", 10000};
	return m;
}

/** Runs one SQL statement on a file directly (to build files the store would not write). */
void execSql(const std::string& path, const std::string& sql)
{
	sqlite3* db = nullptr;
	ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
	char* err = nullptr;
	const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err);
	const std::string msg = err ? err : "";
	sqlite3_free(err);
	sqlite3_close(db);
	ASSERT_EQ(rc, SQLITE_OK) << msg;
}

/** The message of the exception Open() throws ("" when it does not throw). */
std::string openError(const std::string& path)
{
	try
	{
		SessionStore::Open(path);
	}
	catch (const std::exception& e)
	{
		return e.what();
	}
	return "";
}

LoopConstraint testLoop(KeyFrameId cur, KeyFrameId old)
{
	LoopConstraint l;
	l.keyframe = cur;
	l.loopKeyFrame = old;
	l.T_loop_cur = mrpt::poses::CPose3D(0.1, -0.2, 0.05, 0.3, -0.01, 0.02);
	for (int r = 0; r < 6; r++)
		for (int c = 0; c < 6; c++) l.information(r, c) = r == c ? 100.0 + r : 0.5 / (1 + r + c);
	l.score = 0.0421;
	l.inliers = 57;
	return l;
}
}  // namespace

TEST(SessionStore, RoundTripOfEveryRecord)
{
	const std::string path = test::scratchDir("store_roundtrip") + "/session.kgmap";
	const KeyFrameImageCodec codec;
	std::vector<KeyFrameRecord> kfs;
	std::vector<KeyFrameImages> images;
	mrpt::maps::CSimplePointsMap points;
	for (int i = 0; i < 100; i++) points.insertPoint(0.01f * i, -0.5f + 0.02f * i, 1.0f / (1 + i));
	{
		auto store = SessionStore::Create(path, testMeta());
		for (KeyFrameId id = 0; id < 3; id++)
		{
			SessionUpdate u;
			u.keyframes.push_back(test::syntheticKeyFrame(id, 1000));
			kfs.push_back(u.keyframes.back());
			// keyframe 0: colour, 1: grey, 2: no images
			KeyFrameImages img;
			if (id < 2)
			{
				img.colour = test::syntheticImage(id, id == 0);
				img.depthRaw = test::syntheticDepthRaw(id);
				u.images.push_back(codec.encode(img.colour, img.depthRaw));
			}
			images.push_back(img);
			for (int k = 0; k < 5; k++) u.landmarks.push_back(test::syntheticLandmark(id * 1000 + k, id, 1 + k));
			if (id > 0) u.covisibility.push_back({id, id - 1, 40 + static_cast<int>(id)});
			if (id == 2)
			{
				u.loops.push_back(testLoop(2, 0));
				u.snapshots.push_back(MapSnapshotCodec::encode("hoc_points", points, 2));
			}
			store.write(u);
		}
	}
	auto store = SessionStore::Open(path);
	EXPECT_EQ(store.mode(), SessionStore::Mode::ReadOnly);
	EXPECT_EQ(store.meta().schemaVersion, SessionStore::kSchemaVersion);
	EXPECT_FALSE(store.meta().keygridVersion.empty());
	EXPECT_EQ(store.meta().createdUtc.size(), 20u) << store.meta().createdUtc;
	EXPECT_EQ(store.meta().vocabulary, testMeta().vocabulary);
	test::expectSameCamera(store.meta().camera, testMeta().camera);

	const auto loaded = store.loadKeyFrames();
	ASSERT_EQ(loaded.size(), 3u);
	for (std::size_t i = 0; i < 3; i++) expectSameKeyFrame(kfs[i], loaded[i]);
	const auto one = store.loadKeyFrame(1);
	ASSERT_TRUE(one.has_value());
	expectSameKeyFrame(kfs[1], *one);
	EXPECT_FALSE(store.loadKeyFrame(7).has_value());

	for (KeyFrameId id = 0; id < 3; id++)
	{
		const auto img = store.loadImages(id);
		EXPECT_TRUE(sameBits(img.colour, images[id].colour)) << "keyframe " << id;
		EXPECT_TRUE(sameBits(img.depthRaw, images[id].depthRaw)) << "keyframe " << id;
	}
	EXPECT_EQ(store.loadImages(0).colour.type(), CV_8UC3);
	EXPECT_EQ(store.loadImages(1).colour.type(), CV_8UC1);

	const auto lms = store.loadLandmarks();
	ASSERT_EQ(lms.size(), 15u);
	std::size_t n = 0;
	for (KeyFrameId id = 0; id < 3; id++)
		for (int k = 0; k < 5; k++) expectSameLandmark(test::syntheticLandmark(id * 1000 + k, id, 1 + k), lms[n++]);

	test::expectSameCovisibility(store.loadCovisibility(), {{0, 1, 41}, {1, 2, 42}});

	const auto loops = store.loadLoopConstraints();
	ASSERT_EQ(loops.size(), 1u);
	const auto expected = testLoop(2, 0);
	EXPECT_EQ(loops[0].keyframe, 2u);
	EXPECT_EQ(loops[0].loopKeyFrame, 0u);
	test::expectSamePose(loops[0].T_loop_cur, expected.T_loop_cur);
	EXPECT_EQ(loops[0].information, expected.information);
	EXPECT_EQ(loops[0].score, expected.score);
	EXPECT_EQ(loops[0].inliers, expected.inliers);

	EXPECT_EQ(store.snapshotNames(), std::vector<std::string>{"hoc_points"});
	const auto snap = store.loadSnapshot("hoc_points");
	ASSERT_TRUE(snap.has_value());
	EXPECT_EQ(snap->lastKeyFrame, 2u);
	EXPECT_EQ(snap->data, MapSnapshotCodec::encode("hoc_points", points, 2).data);
	const auto obj = std::dynamic_pointer_cast<mrpt::maps::CSimplePointsMap>(MapSnapshotCodec::decode(*snap));
	ASSERT_TRUE(obj);
	ASSERT_EQ(obj->size(), points.size());
	for (std::size_t i = 0; i < points.size(); i++)
	{
		EXPECT_EQ(obj->getPointsBufferRef_x()[i], points.getPointsBufferRef_x()[i]);
		EXPECT_EQ(obj->getPointsBufferRef_y()[i], points.getPointsBufferRef_y()[i]);
		EXPECT_EQ(obj->getPointsBufferRef_z()[i], points.getPointsBufferRef_z()[i]);
	}
	EXPECT_FALSE(store.loadSnapshot("map_2d").has_value());

	const auto c = store.counts();
	EXPECT_EQ(c.keyframes, 3u);
	EXPECT_EQ(c.keyframesWithImages, 2u);
	EXPECT_EQ(c.landmarks, 15u);
	EXPECT_EQ(c.covisibilityEdges, 2u);
	EXPECT_EQ(c.loopConstraints, 1u);
	EXPECT_EQ(c.snapshots, 1u);
}

TEST(SessionStore, UpsertsPosesAndErasures)
{
	const std::string path = test::scratchDir("store_upsert") + "/session.kgmap";
	{
		auto store = SessionStore::Create(path, testMeta());
		SessionUpdate u;
		for (KeyFrameId id = 0; id < 3; id++)
		{
			u.keyframes.push_back(test::syntheticKeyFrame(id, 50));
			u.images.push_back(KeyFrameImageCodec().encode(test::syntheticImage(id, false, 64, 48), test::syntheticDepthRaw(id, 64, 48)));
		}
		u.landmarks = {test::syntheticLandmark(1, 0, 2), test::syntheticLandmark(2, 0, 3)};
		u.covisibility = {{0, 1, 30}, {2, 1, 20}, {0, 2, 15}};
		u.snapshots.push_back({"map_2d", 1, {1, 2, 3}});
		store.write(u);

		SessionUpdate v;
		auto changed = test::syntheticLandmark(1, 0, 2);
		changed.p_world = {1.5, -2.25, 0.125};
		changed.observations[2] = 77;
		changed.hocCounts.assign(60, 3);
		v.landmarks.push_back(changed);
		v.poses.push_back({1, mrpt::poses::CPose3D(1, 2, 3, 0.1, 0.2, 0.3)});
		KeyFrameLandmarks assoc{0, std::vector<LandmarkId>(50, kNoLandmark)};
		assoc.landmarks[7] = 1;
		v.associations.push_back(assoc);
		v.erasedKeyFrames.push_back(2);
		v.erasedLandmarks.push_back(2);
		v.covisibility.push_back({1, 0, 0});  // weight 0 removes the edge
		v.snapshots.push_back({"map_2d", 2, {4, 5}});
		v.attributes["run.tracking_share_median"] = "0.25";
		store.write(v);
		EXPECT_EQ(store.meta().attributes.at("run.tracking_share_median"), "0.25");
		SessionUpdate badKey;
		badKey.attributes["camera_fx"] = "1";
		EXPECT_THROW(store.write(badKey), std::invalid_argument) << "only run.* keys: the store's own meta rows are not attributes";

		SessionUpdate bad;
		bad.poses.push_back({9, mrpt::poses::CPose3D()});
		bad.landmarks.push_back(test::syntheticLandmark(5, 0, 1));
		EXPECT_THROW(store.write(bad), std::invalid_argument);
		SessionUpdate wrongLength;
		wrongLength.associations.push_back({0, std::vector<LandmarkId>(49, kNoLandmark)});
		EXPECT_THROW(store.write(wrongLength), std::invalid_argument) << "one entry per keypoint";
	}
	auto store = SessionStore::Open(path);
	EXPECT_EQ(store.meta().attributes, (std::map<std::string, std::string>{{"run.tracking_share_median", "0.25"}}));
	EXPECT_DOUBLE_EQ(store.meta().camera.fx, testMeta().camera.fx) << "a refused attribute changes nothing";
	const auto kfs = store.loadKeyFrames();
	ASSERT_EQ(kfs.size(), 2u);
	test::expectSamePose(kfs[1].T_world_cam, mrpt::poses::CPose3D(1, 2, 3, 0.1, 0.2, 0.3));
	std::vector<LandmarkId> expected(50, kNoLandmark);
	expected[7] = 1;
	EXPECT_EQ(kfs[0].landmarks, expected);
	EXPECT_TRUE(store.loadEncodedImages(2).empty());
	EXPECT_FALSE(store.loadEncodedImages(1).empty());
	const auto lms = store.loadLandmarks();
	ASSERT_EQ(lms.size(), 1u) << "the landmark of the rolled-back write must not be there";
	EXPECT_EQ(lms[0].p_world, Eigen::Vector3d(1.5, -2.25, 0.125));
	EXPECT_EQ(lms[0].observations.at(2), 77);
	EXPECT_EQ(lms[0].hocCounts, std::vector<std::int16_t>(60, 3));
	EXPECT_TRUE(store.loadCovisibility().empty()) << "(0,1) set to weight 0, (1,2) and (0,2) went with keyframe 2";
	const auto snap = store.loadSnapshot("map_2d");
	ASSERT_TRUE(snap.has_value());
	EXPECT_EQ(snap->lastKeyFrame, 2u);
	EXPECT_EQ(snap->data, (std::vector<std::uint8_t>{4, 5}));
}

TEST(SessionStore, ReopenToExtendAndReadOnlyRefusesWrites)
{
	const std::string path = test::scratchDir("store_extend") + "/session.kgmap";
	{
		auto store = SessionStore::Create(path, testMeta());
		SessionUpdate u;
		u.keyframes.push_back(test::syntheticKeyFrame(0, 20));
		store.write(u);
	}
	EXPECT_THROW(SessionStore::Create(path, testMeta()), std::runtime_error);
	{
		auto store = SessionStore::Open(path, SessionStore::Mode::ReadWrite);
		SessionUpdate u;
		u.keyframes.push_back(test::syntheticKeyFrame(1, 20));
		u.keyframes.back().camera = core::RgbdCamera::Preset("fr2");
		store.write(u);
		store.setVocabulary({"other.bin", "fedcba9876543210", 1000});
	}
	auto store = SessionStore::Open(path);
	const auto kfs = store.loadKeyFrames();
	ASSERT_EQ(kfs.size(), 2u);
	test::expectSameCamera(kfs[0].camera, core::RgbdCamera::Preset("fr1"));
	test::expectSameCamera(kfs[1].camera, core::RgbdCamera::Preset("fr2"));
	EXPECT_EQ(store.meta().vocabulary.hash, "fedcba9876543210");
	EXPECT_THROW(store.write(SessionUpdate{}), std::logic_error);
}

TEST(SessionStore, RejectsInconsistentRecords)
{
	const std::string path = test::scratchDir("store_invalid") + "/session.kgmap";
	auto store = SessionStore::Create(path, testMeta());
	SessionUpdate u;
	u.keyframes.push_back(test::syntheticKeyFrame(4, 20));
	u.keyframes.back().keypointDepth.pop_back();
	try
	{
		store.write(u);
		FAIL() << "no exception";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("keyframe 4: keypointDepth has 19 entries for 20 keypoints"), std::string::npos)
			<< e.what();
	}
	SessionUpdate self;
	self.covisibility.push_back({3, 3, 10});
	EXPECT_THROW(store.write(self), std::invalid_argument);
	EXPECT_EQ(store.counts().keyframes, 0u);
}

TEST(SessionStore, OtherSchemaVersionIsRefusedNamingBothVersions)
{
	const std::string path = test::scratchDir("store_version") + "/session.kgmap";
	SessionStore::Create(path, testMeta());
	execSql(path, "UPDATE meta SET value = '2' WHERE key = 'schema_version'");
	const std::string err = openError(path);
	EXPECT_NE(err.find(path), std::string::npos) << err;
	EXPECT_NE(err.find("schema version 2"), std::string::npos) << err;
	EXPECT_NE(err.find("reads version 1"), std::string::npos) << err;
	EXPECT_THROW(SessionStore::Check(path), std::runtime_error);
}

TEST(SessionStore, FilesThatAreNotSessionsAreRefused)
{
	const std::string dir = test::scratchDir("store_notastore");
	const std::string text = dir + "/notes.txt";
	std::ofstream(text) << std::string(10000, 'x');
	std::string err = openError(text);
	EXPECT_NE(err.find(text), std::string::npos) << err;
	EXPECT_NE(err.find("not a keygrid session"), std::string::npos) << err;

	const std::string other = dir + "/other.sqlite";
	execSql(other, "CREATE TABLE t(x INTEGER); INSERT INTO t VALUES(1);");
	err = openError(other);
	EXPECT_NE(err.find("not a keygrid session (SQLite application_id 0x00000000"), std::string::npos) << err;

	err = openError(dir + "/missing.kgmap");
	EXPECT_NE(err.find("missing.kgmap' does not exist"), std::string::npos) << err;
}

TEST(SessionStore, DamagedFileIsRefused)
{
	const std::string path = test::scratchDir("store_damaged") + "/session.kgmap";
	{
		auto store = SessionStore::Create(path, testMeta());
		for (KeyFrameId id = 0; id < 6; id++)
		{
			SessionUpdate u;
			u.keyframes.push_back(test::syntheticKeyFrame(id, 1000));
			u.images.push_back(KeyFrameImageCodec().encode(test::syntheticImage(id, true), test::syntheticDepthRaw(id)));
			for (int k = 0; k < 200; k++) u.landmarks.push_back(test::syntheticLandmark(id * 1000 + k, id, 2));
			store.write(u);
		}
	}
	ASSERT_FALSE(std::filesystem::exists(path + "-wal")) << "closing the last connection checkpoints the log";
	EXPECT_EQ(openError(path), "");
	// Overwrite 16 pages (4 KiB each) in the middle of the file with a byte pattern.
	const auto size = std::filesystem::file_size(path);
	ASSERT_GT(size, 1'000'000u);
	{
		std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
		f.seekp(static_cast<std::streamoff>((size / 2) / 4096 * 4096));
		const std::string garbage(16 * 4096, '\xA5');
		f.write(garbage.data(), static_cast<std::streamsize>(garbage.size()));
	}
	const std::string err = openError(path);
	EXPECT_NE(err.find(path), std::string::npos) << err;
	EXPECT_NE(err.find("is damaged"), std::string::npos) << err;
	EXPECT_THROW(SessionStore::Check(path), std::runtime_error);

	// A file cut short.
	const std::string cut = test::scratchDir("store_truncated") + "/session.kgmap";
	std::filesystem::copy_file(path, cut);
	std::filesystem::resize_file(cut, size / 3);
	const std::string errCut = openError(cut);
	EXPECT_NE(errCut.find("is damaged"), std::string::npos) << errCut;
}

TEST(SessionStoreOptions, IniRoundTripAndErrorsNameTheKey)
{
	SessionStoreOptions o;
	EXPECT_NO_THROW(o.validate());
	o.durability = "normal";
	o.cacheSizeKiB = 4096;
	o.busyTimeoutMs = 100;
	o.integrityCheck = "none";
	mrpt::config::CConfigFileMemory saved;
	o.saveToConfigFile(saved, "store");
	// Through the text, as a saved file is read (comments are stripped when text is parsed).
	mrpt::config::CConfigFileMemory ini(saved.getContent());
	SessionStoreOptions back;
	back.loadFromConfigFile(ini, "store");
	EXPECT_EQ(back.durability, "normal");
	EXPECT_EQ(back.cacheSizeKiB, 4096);
	EXPECT_EQ(back.busyTimeoutMs, 100);
	EXPECT_EQ(back.integrityCheck, "none");
	ini.write("store", "durability", "sometimes");
	try
	{
		back.loadFromConfigFile(ini, "store");
		FAIL() << "no exception";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("durability"), std::string::npos) << e.what();
	}
	EXPECT_THROW(SessionStore::Create(test::scratchDir("store_opts") + "/s.kgmap", testMeta(), back), std::invalid_argument);
}
