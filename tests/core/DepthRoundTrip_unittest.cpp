// TUM PNG -> CObservation3DRangeScan -> rawlog -> Frame keeps depth bit-exact (raw and metres).
#include <keygrid/core/RawlogFrameSource.h>
#include <keygrid/core/RawlogWriter.h>
#include <keygrid/core/RgbdObservation.h>
#include <keygrid/core/TumFrameSource.h>

#include "SyntheticTum.h"
#include "TestChecks.h"
#include "TestData.h"

#include <cstring>

using namespace keygrid::core;
using keygrid::test::sameBits;

namespace
{
void roundTrip(const std::string& tumDir, const std::string& out, bool external, const FrameSourceOptions& so)
{
	TumFrameSource tum(tumDir, so);
	RawlogWriterOptions wo;
	wo.externalImages = external;
	std::size_t written = 0;
	{
		RawlogWriter w(out, wo);
		Frame f;
		for (; tum.next(f); written++) w.write(makeRgbdObservation(f));
		w.close();
	}
	ASSERT_GT(written, 0u) << "no frame read from " << tumDir;
	TumFrameSource again(tumDir, so);
	RawlogFrameSource rl(out);
	Frame a, b;
	std::size_t n = 0;
	while (again.next(a))
	{
		ASSERT_TRUE(rl.next(b)) << "rawlog ended early at frame " << n;
		EXPECT_TRUE(sameBits(a.depthRaw, b.depthRaw)) << "raw depth differs at frame " << n;
		EXPECT_TRUE(sameBits(a.depth, b.depth)) << "metric depth differs at frame " << n;
		EXPECT_TRUE(sameBits(a.colour, b.colour)) << "colour differs at frame " << n;
		EXPECT_TRUE(sameBits(a.grey, b.grey));
		EXPECT_NEAR(a.timestamp, b.timestamp, 1e-6);  // MRPT stores 100 ns ticks
		EXPECT_DOUBLE_EQ(a.camera.fx, b.camera.fx);
		EXPECT_DOUBLE_EQ(a.camera.dist[4], b.camera.dist[4]);
		EXPECT_FLOAT_EQ(b.camera.depthUnits, 0.0002f);
		++n;
	}
	EXPECT_FALSE(rl.next(b));
	EXPECT_EQ(n, written);
	EXPECT_EQ(rl.skippedCount(), 0u);
}
}  // namespace

TEST(DepthRoundTrip, SyntheticFullRangeDepthIsBitExact)
{
	const std::string dir = keygrid::test::scratchDir("roundtrip_synth");
	const auto s = keygrid::test::writeSyntheticTum(dir + "/tum", 4);
	FrameSourceOptions so;
	so.camera = RgbdCamera::Preset("fr1");
	so.camera->width = 64;
	so.camera->height = 48;
	roundTrip(s.dir, dir + "/out.rawlog", false, so);
	roundTrip(s.dir, dir + "/ext.rawlog", true, so);
	// The raw values are the PNG's, and metres are raw / 5000 exactly as the single converter gives.
	RawlogFrameSource rl(dir + "/ext.rawlog");
	Frame f;
	ASSERT_TRUE(rl.next(f));
	EXPECT_EQ(f.depthRaw.at<uint16_t>(0, 1), 65535);
	EXPECT_FLOAT_EQ(f.depth.at<float>(0, 1), 65535 * 0.0002f);
	EXPECT_EQ(f.depth.at<float>(0, 0), 0.0f);
	EXPECT_TRUE(sameBits(f.depthRaw, s.depthRaw[0]));
}

TEST(DepthRoundTrip, RealFr1DeskIsBitExact)
{
	KEYGRID_SKIP_WITHOUT_SHARED_DATA("tum_fr1_desk_9frames");
	roundTrip(
		keygrid::test::sharedDataDir() + "/tum_fr1_desk_9frames",
		keygrid::test::scratchDir("roundtrip_fr1") + "/desk.rawlog", false, {});
}
