/** \file KeyFrameImages_unittest.cpp
 * Keyframe images out of RAM: KeyFrameImageCache keeps at most its capacity in RAM
 * (least recently used evicted first) and gives back every image bit-identical from its spill
 * file, which leaves no file behind; StoredKeyFrameImages gives back what a session file holds,
 * the depth bit-identical in metres.
 */
#include <keygrid/slam/KeyFrameImageCache.h>
#include <keygrid/slam/SessionRecorder.h>
#include <keygrid/slam/StoredKeyFrameImages.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <keygrid/store/KeyFrameImageCodec.h>
#include <keygrid/store/SessionStore.h>
#include <keygrid/store/SparseMapRecords.h>

#include <cstring>
#include <filesystem>
#include <limits>
#include <random>

#include "TestChecks.h"
#include "TestData.h"

using namespace keygrid;
using namespace keygrid::slam;
using keygrid::test::sameBits;

namespace
{
constexpr float kDepthUnits = 0.0002f;

/** Depth in metres as sensors give it (a multiple of the depth units, some holes), seeded. */
cv::Mat depthImage(int seed, int rows = 48, int cols = 64)
{
	std::mt19937 rng(static_cast<unsigned>(seed));
	cv::Mat raw(rows, cols, CV_16UC1);
	for (int r = 0; r < rows; r++)
		for (int c = 0; c < cols; c++) raw.at<uint16_t>(r, c) = rng() % 7 == 0 ? 0 : static_cast<uint16_t>(2000 + rng() % 40000);
	return store::KeyFrameImageCodec::rawToDepth(raw, kDepthUnits);
}

cv::Mat colourImage(int seed, bool bgr = true, int rows = 48, int cols = 64)
{
	cv::Mat m(rows, cols, bgr ? CV_8UC3 : CV_8UC1);
	cv::RNG rng(static_cast<uint64_t>(seed) + 1);
	rng.fill(m, cv::RNG::UNIFORM, cv::Scalar::all(0), cv::Scalar::all(256));
	return m;
}

std::size_t bytesOf(const KeyFrameImageData& d) { return d.depth.total() * d.depth.elemSize() + d.colour.total() * d.colour.elemSize(); }
}  // namespace

TEST(KeyFrameImageCache, GivesBackEveryImageBitIdenticalFromTheSpillFile)
{
	KeyFrameImageCache cache(0);  // nothing kept in RAM: every get() reads the file
	std::vector<KeyFrameImageData> put;
	for (int id = 0; id < 5; id++)
	{
		KeyFrameImageData d{depthImage(id), colourImage(id, id % 2 == 0)};
		// Odd bit patterns survive too (NaN, -0, denormals): the file holds the bytes.
		d.depth.at<float>(0, 0) = std::numeric_limits<float>::quiet_NaN();
		d.depth.at<float>(0, 1) = -0.0f;
		d.depth.at<float>(0, 2) = std::numeric_limits<float>::denorm_min();
		cache.put(static_cast<sfm::KeyFrameId>(id), {d.depth.clone(), d.colour.clone()});
		put.push_back(d);
	}
	EXPECT_EQ(cache.cachedCount(), 0u);
	EXPECT_GT(cache.spilledBytes(), 0u);
	for (int id = 4; id >= 0; id--)
	{
		const auto got = cache.get(static_cast<sfm::KeyFrameId>(id));
		EXPECT_TRUE(sameBits(got.depth, put[id].depth)) << id;
		EXPECT_TRUE(sameBits(got.colour, put[id].colour)) << id;
	}
	EXPECT_EQ(cache.stats().misses, 5u);
	EXPECT_EQ(cache.stats().hits, 0u);
	EXPECT_THROW(cache.get(9), std::out_of_range);
	EXPECT_FALSE(cache.contains(9));
}

TEST(KeyFrameImageCache, KeepsAtMostItsCapacityEvictingTheLeastRecentlyUsed)
{
	const KeyFrameImageData one{depthImage(0), colourImage(0)};
	const std::size_t b = bytesOf(one);
	KeyFrameImageCache cache(2 * b + b / 2);  // room for two keyframes
	for (sfm::KeyFrameId id = 0; id < 3; id++) cache.put(id, {depthImage(static_cast<int>(id)), colourImage(static_cast<int>(id))});
	EXPECT_EQ(cache.cachedCount(), 2u);
	EXPECT_EQ(cache.cachedBytes(), 2 * b);
	EXPECT_LE(cache.cachedBytes(), cache.capacityBytes());
	EXPECT_EQ(cache.stats().evictions, 1u);  // keyframe 0
	EXPECT_EQ(cache.spilledBytes(), b) << "only evicted images are written to the spill file";

	cache.get(1);  // hit: 1 becomes the most recent, 2 the least
	EXPECT_EQ(cache.stats().hits, 1u);
	const auto zero = cache.get(0);  // miss: read back, 2 evicted
	EXPECT_EQ(cache.stats().misses, 1u);
	EXPECT_TRUE(sameBits(zero.depth, depthImage(0)));
	EXPECT_EQ(cache.stats().evictions, 2u);
	EXPECT_EQ(cache.spilledBytes(), 2 * b) << "keyframe 0 is not written twice";
	cache.get(1);
	EXPECT_EQ(cache.stats().hits, 2u);  // 1 stayed
	cache.get(2);
	EXPECT_EQ(cache.stats().misses, 2u);  // 2 had gone
	EXPECT_EQ(cache.cachedCount(), 2u);

	// Images larger than the whole cache are not kept, but still given back.
	KeyFrameImageCache tiny(b / 2);
	tiny.put(7, one);
	EXPECT_EQ(tiny.cachedCount(), 0u);
	EXPECT_TRUE(sameBits(tiny.get(7).colour, one.colour));
}

TEST(KeyFrameImageCache, PrefersTheKeyframesOwnImagesAndLeavesNoFileBehind)
{
	const std::string dir = test::scratchDir("image_cache_spill");
	{
		KeyFrameImageCache cache(1 << 20, dir);
		cache.put(3, {depthImage(3), colourImage(3)});
		EXPECT_TRUE(std::filesystem::is_empty(dir)) << "the spill file is unlinked at once";
		sfm::KeyFrame kf;
		kf.id = 3;
		EXPECT_TRUE(cache.hasImages(kf));
		EXPECT_TRUE(sameBits(cache.load(kf).depth, depthImage(3)));
		kf.depth = depthImage(4);
		kf.colour = colourImage(4, false);
		EXPECT_TRUE(sameBits(cache.load(kf).colour, colourImage(4, false)));
		kf.colour.release();
		EXPECT_FALSE(cache.hasImages(kf)) << "a keyframe holding only depth has no image";
		kf.depth.release();
		kf.id = 5;
		EXPECT_FALSE(cache.hasImages(kf));
		EXPECT_TRUE(cache.load(kf).depth.empty());
	}
	EXPECT_TRUE(std::filesystem::is_empty(dir));
	EXPECT_THROW(KeyFrameImageCache(1, dir + "/missing"), std::runtime_error);
}

TEST(StoredKeyFrameImages, GivesBackTheSessionImagesDepthBitIdenticalInMetres)
{
	const std::string path = test::scratchDir("stored_images") + "/s.kgmap";
	std::vector<sfm::KeyFrame> kfs(2);
	{
		auto st = store::SessionStore::Create(path, store::SessionMeta{});
		store::SessionUpdate u;
		store::KeyFrameImageCodec codec(store::ImageCodecOptions{});
		for (int i = 0; i < 2; i++)
		{
			auto& kf = kfs[i];
			kf.id = static_cast<sfm::KeyFrameId>(i);
			kf.features.camera.depthUnits = kDepthUnits;
			u.keyframes.push_back(store::toRecord(kf, loop::BowVector{}));
			// keyframe 1 has no depth
			const cv::Mat raw = i == 0 ? store::KeyFrameImageCodec::depthToRaw(depthImage(i), kDepthUnits) : cv::Mat();
			u.images.push_back(codec.encode(colourImage(i, i == 0), raw));
		}
		st.write(u);
	}
	const auto st = store::SessionStore::Open(path);
	const StoredKeyFrameImages images(st);
	EXPECT_TRUE(images.hasImages(kfs[0]));
	EXPECT_FALSE(images.hasImages(kfs[1]));
	const auto got = images.load(kfs[0]);
	EXPECT_TRUE(sameBits(got.depth, depthImage(0)));
	EXPECT_TRUE(sameBits(got.colour, colourImage(0, true)));
	EXPECT_TRUE(images.load(kfs[1]).depth.empty());
	EXPECT_TRUE(sameBits(images.load(kfs[1]).colour, colourImage(1, false)));
}

TEST(KeyFrameImageCache, CapacityIsTheStoreSectionsImageCacheMib)
{
	SessionRecorderOptions o;
	EXPECT_EQ(o.imageCacheMib, 16);
	mrpt::config::CConfigFileMemory c;
	c.write("store", "image_cache_mib", 32);
	o.loadFromConfigFile(c, "store");
	EXPECT_EQ(o.imageCacheMib, 32);
	for (const char* bad : {"-1", "2000000", "lots"})
	{
		mrpt::config::CConfigFileMemory b;
		b.write("store", "image_cache_mib", std::string(bad));
		try
		{
			SessionRecorderOptions(o).loadFromConfigFile(b, "store");
			ADD_FAILURE() << bad << " accepted";
		}
		catch (const std::invalid_argument& e)
		{
			EXPECT_NE(std::string(e.what()).find("image_cache_mib"), std::string::npos) << e.what();
		}
	}
}
