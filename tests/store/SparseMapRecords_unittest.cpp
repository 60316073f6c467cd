/** \file SparseMapRecords_unittest.cpp
 * sfm::KeyFrame / sfm::Landmark -> store -> back, field by field; vocabulary identities.
 */
#include <keygrid/core/Frame.h>
#include <keygrid/loop/Vocabulary.h>
#include <keygrid/store/SessionStore.h>
#include <keygrid/store/SparseMapRecords.h>
#include <keygrid/store/VocabularyFingerprint.h>

#include <sstream>

#include "StoreTestHelpers.h"
#include "SyntheticSession.h"
#include "TestData.h"

using namespace keygrid;
using namespace keygrid::store;

namespace
{
/** `images` "images" of `rows` uniformly random 32-byte descriptors, image i filled by
 * cv::RNG(firstSeed + i). */
std::vector<cv::Mat> randomDescriptorImages(int images, int rows, int firstSeed)
{
	std::vector<cv::Mat> out;
	for (int i = 0; i < images; i++)
	{
		cv::Mat d(rows, 32, CV_8U);
		cv::RNG(static_cast<std::uint64_t>(firstSeed + i)).fill(d, cv::RNG::UNIFORM, 0, 256);
		out.push_back(d);
	}
	return out;
}

/** Single-threaded training options of a small `branching` x 2 tree. */
loop::VocabularyOptions smallTreeOptions(int branching)
{
	loop::VocabularyOptions o;
	o.branching = branching;
	o.levels = 2;
	o.threads = 1;
	return o;
}
}  // namespace

TEST(SparseMapRecords, KeyFramesAndLandmarksThroughTheStore)
{
	const auto rec = test::syntheticKeyFrame(12, 300);
	sfm::KeyFrame kf = toKeyFrame(rec);
	kf.colour = test::syntheticImage(12, true);
	kf.depth = core::depthRawToMetres(test::syntheticDepthRaw(12), kf.features.camera.depthUnits);
	kf.covisibility = {{3, 40}, {20, 17}};
	sfm::Landmark lm = toLandmark(test::syntheticLandmark(12001, 12, 3));
	lm.hoc.add(7, 2, 20, 60);

	const std::string path = test::scratchDir("store_sfm") + "/session.kgmap";
	{
		auto store = SessionStore::Create(path, SessionMeta{});
		SessionUpdate u;
		u.keyframes.push_back(toRecord(kf, rec.bow));
		u.images.push_back(encodeImages(kf, KeyFrameImageCodec()));
		u.landmarks.push_back(toRecord(lm));
		u.covisibility = covisibilityOf(kf);
		store.write(u);
	}
	const auto store = SessionStore::Open(path);
	const auto kfs = store.loadKeyFrames();
	ASSERT_EQ(kfs.size(), 1u);
	test::expectSameKeyFrame(rec, kfs[0]);
	const sfm::KeyFrame back = toKeyFrame(kfs[0]);
	EXPECT_EQ(back.features.featuresInArea(rec.undistorted[5].x, rec.undistorted[5].y, 1.0f).size(),
			  kf.features.featuresInArea(rec.undistorted[5].x, rec.undistorted[5].y, 1.0f).size())
		<< "the lookup grid is rebuilt";
	const auto img = store.loadImages(12);
	EXPECT_TRUE(test::sameBits(img.colour, kf.colour));
	EXPECT_TRUE(test::sameBits(KeyFrameImageCodec::rawToDepth(img.depthRaw, rec.camera.depthUnits), kf.depth));

	const auto lms = store.loadLandmarks();
	ASSERT_EQ(lms.size(), 1u);
	const sfm::Landmark lmBack = toLandmark(lms[0]);
	EXPECT_EQ(lmBack.p_world, lm.p_world);
	EXPECT_EQ(lmBack.observations, lm.observations);
	EXPECT_EQ(lmBack.hoc.counts(), lm.hoc.counts());
	EXPECT_EQ(lmBack.hoc.count(7), lms[0].hocCounts[7]);
	EXPECT_TRUE(test::sameBits(lmBack.descriptor, lm.descriptor));

	test::expectSameCovisibility(store.loadCovisibility(), {{3, 12, 40}, {12, 20, 17}});
}

TEST(VocabularyFingerprint, FileAndObjectGiveTheSameIdentity)
{
	EXPECT_EQ(fnv1a64Hex("", 0), "cbf29ce484222325");
	EXPECT_EQ(fnv1a64Hex("a", 1), "af63dc4c8601ec8c");
	const std::vector<cv::Mat> images = randomDescriptorImages(4, 200, 1);
	loop::VocabularyOptions o = smallTreeOptions(4);
	const auto voc = loop::Vocabulary::train(images, o);
	const std::string path = test::scratchDir("store_vocab") + "/small_voc.bin";
	voc.save(path);
	const auto a = vocabularyIdentity(voc, "/somewhere/small_voc.bin");
	const auto b = vocabularyIdentityOfFile(path);
	EXPECT_EQ(a, b);
	EXPECT_EQ(a.fileName, "small_voc.bin");
	EXPECT_EQ(a.words, voc.numWords());
	EXPECT_EQ(a.hash.size(), 16u);
	o.seed = 2;
	EXPECT_NE(vocabularyIdentity(loop::Vocabulary::train(images, o), "small_voc.bin").hash, a.hash);
	EXPECT_THROW(vocabularyIdentityOfFile(path + ".missing"), std::runtime_error);
}

TEST(VocabularyFingerprint, AVocabularyStoredInTheSessionComesBackWithItsIdentity)
{
	const auto voc = loop::Vocabulary::train(randomDescriptorImages(3, 150, 10), smallTreeOptions(3));
	const std::string path = test::scratchDir("store_vocab_blob") + "/s.kgmap";
	{
		auto store = SessionStore::Create(path, SessionMeta{});
		EXPECT_FALSE(store.hasStoredVocabulary());
		EXPECT_FALSE(store.loadVocabulary().has_value());
		store.storeVocabulary(voc, "in_run");
	}
	{
		const auto store = SessionStore::Open(path);
		EXPECT_TRUE(store.hasStoredVocabulary());
		EXPECT_EQ(store.meta().vocabulary, vocabularyIdentity(voc, "in_run"));
		const auto back = store.loadVocabulary();
		ASSERT_TRUE(back.has_value());
		std::ostringstream a, b;
		voc.save(a);
		back->save(b);
		EXPECT_EQ(a.str(), b.str());
	}
	{
		auto store = SessionStore::Open(path, SessionStore::Mode::ReadWrite);
		store.setVocabulary({"other.bin", "0000000000000000", 9});
	}
	try
	{
		SessionStore::Open(path).loadVocabulary();
		FAIL() << "no exception";
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_NE(std::string(e.what()).find("is damaged: the stored vocabulary hashes to"), std::string::npos) << e.what();
	}
}
