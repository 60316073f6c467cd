/** \file SessionWriter_unittest.cpp
 * The writer thread commits every submitted update in order with its images encoded (exact for
 * PNG, depth [m] back to raw units), in threaded and sequential mode, and reports a failed
 * update at the next call without writing anything after it.
 */
#include <keygrid/core/Frame.h>
#include <keygrid/store/SessionWriter.h>

#include "StoreTestHelpers.h"
#include "SyntheticSession.h"
#include "TestData.h"

using namespace keygrid;
using namespace keygrid::store;

namespace
{
SessionWriteJob jobFor(KeyFrameId id)
{
	SessionWriteJob job;
	job.update.keyframes.push_back(test::syntheticKeyFrame(id, 200));
	job.update.landmarks.push_back(test::syntheticLandmark(id * 1000 + 1, id, 1));
	if (id > 0) job.update.covisibility.push_back({id - 1, id, 30});
	KeyFrameImageSource img;
	img.colour = test::syntheticImage(id, id % 2 == 0);
	// Even keyframes give depth in metres (as sfm::KeyFrame holds it), odd ones raw units.
	img.depth = id % 2 == 0 ? core::depthRawToMetres(test::syntheticDepthRaw(id), 0.0002f) : test::syntheticDepthRaw(id);
	img.depthUnits = 0.0002f;
	job.images.push_back(img);
	return job;
}
}  // namespace

TEST(SessionWriter, CommitsEveryUpdateWithItsImagesInOrder)
{
	for (const bool threaded : {true, false})
	{
		SCOPED_TRACE(threaded ? "threaded" : "sequential");
		const std::string path = test::scratchDir(threaded ? "writer_threaded" : "writer_sequential") + "/s.kgmap";
		{
			SessionWriterOptions o;
			o.threaded = threaded;
			o.queueCapacity = 2;
			SessionWriter w(SessionStore::Create(path, SessionMeta{}), o);
			for (KeyFrameId id = 0; id < 8; id++) w.submit(jobFor(id));
			w.close();
			EXPECT_EQ(w.stats().committed, 8u);
			EXPECT_GT(w.stats().encodeSeconds, 0.0);
			EXPECT_THROW(w.submit(jobFor(9)), std::logic_error);
		}
		const auto store = SessionStore::Open(path);
		const auto kfs = store.loadKeyFrames();
		ASSERT_EQ(kfs.size(), 8u);
		for (KeyFrameId id = 0; id < 8; id++)
		{
			test::expectSameKeyFrame(test::syntheticKeyFrame(id, 200), kfs[id]);
			const auto img = store.loadImages(id);
			EXPECT_TRUE(test::sameBits(img.colour, test::syntheticImage(id, id % 2 == 0))) << id;
			EXPECT_TRUE(test::sameBits(img.depthRaw, test::syntheticDepthRaw(id))) << id;
		}
		EXPECT_EQ(store.loadLandmarks().size(), 8u);
		EXPECT_EQ(store.loadCovisibility().size(), 7u);
	}
}

TEST(SessionWriter, AFailedUpdateIsReportedAndStopsWriting)
{
	const std::string path = test::scratchDir("writer_error") + "/s.kgmap";
	{
		SessionWriter w(SessionStore::Create(path, SessionMeta{}));
		w.submit(jobFor(0));
		auto bad = jobFor(1);
		bad.update.keyframes[0].landmarks.pop_back();
		w.submit(std::move(bad));
		w.submit(jobFor(2));
		try
		{
			w.flush();
			FAIL() << "no exception";
		}
		catch (const std::runtime_error& e)
		{
			const std::string msg = e.what();
			EXPECT_NE(msg.find(path), std::string::npos) << msg;
			EXPECT_NE(msg.find("keyframe 1: landmarks has 199 entries for 200 keypoints"), std::string::npos) << msg;
		}
		EXPECT_THROW(w.submit(jobFor(3)), std::runtime_error);
	}
	const auto store = SessionStore::Open(path);
	EXPECT_EQ(store.counts().keyframes, 1u) << "nothing after the failed update";
	EXPECT_THROW(SessionWriter(SessionStore::Open(path)), std::invalid_argument);
}
