/** \file KeyFrameImageCodec_unittest.cpp
 * Image compression for the store: PNG round trips are exact, depth [m] <-> raw units is exact
 * for depths that came from raw units, JPEG stays within a few grey levels.
 */
#include <keygrid/core/Frame.h>
#include <keygrid/store/KeyFrameImageCodec.h>
#include <mrpt/config/CConfigFileMemory.h>

#include "StoreTestHelpers.h"
#include "SyntheticSession.h"
#include "TestData.h"

using namespace keygrid;
using namespace keygrid::store;

TEST(KeyFrameImageCodec, PngRoundTripIsExact)
{
	const KeyFrameImageCodec codec;
	for (const bool colour : {true, false})
	{
		const cv::Mat img = test::syntheticImage(3, colour);
		const cv::Mat depth = test::syntheticDepthRaw(3);
		const auto enc = codec.encode(img, depth);
		EXPECT_EQ(enc.colourFormat, "png");
		EXPECT_LT(enc.depth.size(), depth.total() * 2) << "depth PNG compresses";
		const auto dec = KeyFrameImageCodec::decode(enc);
		EXPECT_TRUE(test::sameBits(dec.colour, img));
		EXPECT_TRUE(test::sameBits(dec.depthRaw, depth));
	}
	const auto none = KeyFrameImageCodec::decode(codec.encode(cv::Mat(), cv::Mat()));
	EXPECT_TRUE(none.colour.empty());
	EXPECT_TRUE(none.depthRaw.empty());
}

TEST(KeyFrameImageCodec, DepthMetresToRawIsExactForRawDepths)
{
	const float units = 0.0002f;
	const cv::Mat raw = test::syntheticDepthRaw(5);
	// The frame sources compute metres as raw * units in float (core::depthRawToMetres).
	const cv::Mat metres = core::depthRawToMetres(raw, units);
	EXPECT_TRUE(test::sameBits(KeyFrameImageCodec::depthToRaw(metres, units), raw));
	EXPECT_TRUE(test::sameBits(KeyFrameImageCodec::rawToDepth(raw, units), metres));
	cv::Mat odd(1, 4, CV_32F);
	odd.at<float>(0) = std::numeric_limits<float>::quiet_NaN();
	odd.at<float>(1) = -1.f;
	odd.at<float>(2) = 0.0003f;  // 1.5 units rounds to 2
	odd.at<float>(3) = 13.107f;  // 65535 units
	const cv::Mat r = KeyFrameImageCodec::depthToRaw(odd, units);
	EXPECT_EQ(r.at<std::uint16_t>(0), 0);
	EXPECT_EQ(r.at<std::uint16_t>(1), 0);
	EXPECT_EQ(r.at<std::uint16_t>(2), 2);
	EXPECT_EQ(r.at<std::uint16_t>(3), 65535);
	odd.at<float>(3) = 14.f;
	EXPECT_THROW(KeyFrameImageCodec::depthToRaw(odd, units), std::invalid_argument);
}

TEST(KeyFrameImageCodec, JpegIsCloseAndSmaller)
{
	ImageCodecOptions o;
	o.colourFormat = "jpg";
	const cv::Mat img = test::syntheticImage(4, true);
	const auto jpg = KeyFrameImageCodec(o).encode(img, cv::Mat());
	const auto png = KeyFrameImageCodec().encode(img, cv::Mat());
	EXPECT_LT(jpg.colour.size(), png.colour.size());
	const auto dec = KeyFrameImageCodec::decode(jpg);
	ASSERT_EQ(dec.colour.type(), CV_8UC3);
	// The synthetic shapes have saturated colour edges, which JPEG's 4:2:0 chroma subsampling blurs.
	EXPECT_GT(cv::PSNR(dec.colour, img), 25.0);
}

TEST(KeyFrameImageCodec, OptionsValidateAndLoad)
{
	ImageCodecOptions o;
	mrpt::config::CConfigFileMemory ini;
	ini.write("store", "png_compression", 12);
	try
	{
		o.loadFromConfigFile(ini, "store");
		FAIL() << "no exception";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("[store] png_compression = 12 (must be in [0, 9])"), std::string::npos) << e.what();
	}
	ImageCodecOptions p;
	p.colourFormat = "jpg";
	p.jpegQuality = 80;
	mrpt::config::CConfigFileMemory out;
	p.saveToConfigFile(out, "store");
	ImageCodecOptions q;
	// Through the text, as a saved file is read (comments are stripped when text is parsed).
	q.loadFromConfigFile(mrpt::config::CConfigFileMemory(out.getContent()), "store");
	EXPECT_EQ(q.colourFormat, "jpg");
	EXPECT_EQ(q.jpegQuality, 80);
	EXPECT_EQ(q.pngCompression, 1);
	ImageCodecOptions webp;
	webp.colourFormat = "webp";
	EXPECT_THROW(KeyFrameImageCodec{webp}, std::invalid_argument);
	EXPECT_THROW(KeyFrameImageCodec().encode(cv::Mat(4, 4, CV_32F), cv::Mat()), std::invalid_argument);
}
