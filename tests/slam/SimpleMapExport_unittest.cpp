/** \file SimpleMapExport_unittest.cpp
 * keyframes.simplemap written streaming (one keyframe's images at a time, from the image
 * cache) is byte for byte what CSimpleMap's own serialization of the whole map in RAM gives,
 * and MRPT reads it back as that map.
 */
#include <keygrid/core/AtomicOutput.h>
#include <keygrid/slam/KeyFrameImageCache.h>
#include <keygrid/slam/SimpleMapExport.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/serialization/CArchive.h>

#include <fstream>
#include <iterator>

#include "TestData.h"

using namespace keygrid;
using namespace keygrid::slam;

namespace simple_map_export_unittest
{
namespace
{
std::vector<char> fileBytes(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

std::vector<std::uint8_t> serialized(const mrpt::serialization::CSerializable& o)
{
	mrpt::io::CMemoryStream mem;
	mrpt::serialization::archiveFrom(mem) << o;
	const auto* b = static_cast<const std::uint8_t*>(mem.getRawBufferData());
	return {b, b + mem.getTotalBytesCount()};
}

/** Four keyframes with small images (colour, grey, none, colour) at different poses. */
void fillTestMap(sfm::SparseMap& map)
{
	for (int i = 0; i < 4; i++)
	{
		sfm::KeyFrame kf;
		kf.frameIndex = static_cast<std::size_t>(10 * i);
		kf.timestamp = 100.0 + 0.5 * i;
		kf.T_world_cam = mrpt::poses::CPose3D(0.3 * i, -0.1 * i, 0.05 * i, 0.2 * i, -0.1, 0.05 * i);
		kf.features.camera.width = 32;
		kf.features.camera.height = 24;
		kf.features.camera.fx = kf.features.camera.fy = 30.0;
		kf.features.camera.cx = 15.5;
		kf.features.camera.cy = 11.5;
		if (i != 2)
		{
			cv::Mat raw(24, 32, CV_16UC1);
			cv::randu(raw, cv::Scalar(0), cv::Scalar(30000));
			raw.convertTo(kf.depth, CV_32F, kf.features.camera.depthUnits);
			kf.colour = cv::Mat(24, 32, i == 1 ? CV_8UC1 : CV_8UC3);
			cv::randu(kf.colour, cv::Scalar::all(0), cv::Scalar::all(256));
		}
		map.addKeyFrame(std::move(kf));
	}
}
}  // namespace

TEST(SimpleMapExport, StreamedFileIsCSimpleMapsOwnSerialization)
{
	sfm::SparseMap map;
	fillTestMap(map);
	const std::string dir = test::scratchDir("simplemap_stream");
	const auto inRam = keyframesSimpleMap(map);
	ASSERT_EQ(inRam.size(), 3u);  // the keyframe without images is left out
	core::saveGzAtomically(inRam, dir + "/whole.simplemap");

	// The images leave the keyframes for a cache that keeps none in RAM.
	KeyFrameImageCache cache(0);
	for (const auto& [id, kf] : map.keyframes())
	{
		if (!kf.depth.empty()) cache.put(id, {kf.depth, kf.colour});
		map.keyframe(id).depth.release();
		map.keyframe(id).colour.release();
	}
	EXPECT_EQ(writeKeyframesSimpleMap(map, cache, dir + "/streamed.simplemap"), 3u);
	const auto whole = fileBytes(dir + "/whole.simplemap");
	ASSERT_FALSE(whole.empty());
	EXPECT_TRUE(whole == fileBytes(dir + "/streamed.simplemap")) << "the gz files differ";
	EXPECT_EQ(cache.stats().misses, 3u);

	// MRPT reads it back as the map built in RAM.
	mrpt::maps::CSimpleMap back;
	{
		mrpt::io::CFileGZInputStream f(dir + "/streamed.simplemap");
		mrpt::serialization::archiveFrom(f) >> back;
	}
	ASSERT_EQ(back.size(), inRam.size());
	EXPECT_EQ(serialized(back), serialized(inRam));
	const auto obs = std::get<1>(back.get(1))->getObservationByClass<mrpt::obs::CObservation3DRangeScan>();
	ASSERT_TRUE(obs);
	EXPECT_FALSE(obs->hasIntensityImage && obs->intensityImage.isColor()) << "keyframe 1 has a grey image";
}

TEST(SimpleMapExport, EmptyMapStreamsAnEmptySimpleMap)
{
	const std::string dir = test::scratchDir("simplemap_stream_empty");
	EXPECT_EQ(writeKeyframesSimpleMap(sfm::SparseMap(), KeyFrameImagesInRam(), dir + "/a.simplemap"), 0u);
	core::saveGzAtomically(mrpt::maps::CSimpleMap(), dir + "/b.simplemap");
	EXPECT_TRUE(fileBytes(dir + "/a.simplemap") == fileBytes(dir + "/b.simplemap"));
}
}  // namespace simple_map_export_unittest
