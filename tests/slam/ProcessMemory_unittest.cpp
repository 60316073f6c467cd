#include <keygrid/slam/ProcessMemory.h>
#include <keygrid/slam/StageTimings.h>

#include <gtest/gtest.h>

#include <vector>

using keygrid::slam::MemorySampler;

TEST(ProcessMemory, ResidentSetIsPositiveAndBelowItsPeak)
{
	// A megabyte touched page by page is resident now, and so at least once at the peak.
	std::vector<char> block(1 << 20, 1);
	const double now = keygrid::slam::residentMegabytes();
	EXPECT_GT(now, 1.0);
	EXPECT_GE(keygrid::slam::peakResidentMegabytes() + 0.5, now);
	EXPECT_EQ(block[12345], 1);
}

TEST(ProcessMemory, SamplesOncePerMultipleOfTheKeyFrameStep)
{
	MemorySampler s(25);
	// kf count per frame: grows by one, drops by culling (24 -> 23) and jumps 49 -> 51.
	const std::vector<std::size_t> kfs{0, 10, 24, 25, 25, 26, 24, 25, 49, 51, 52, 74, 75};
	for (std::size_t f = 0; f < kfs.size(); f++) s.onFrame(kfs[f], f + 1, 100.0 + kfs[f]);
	ASSERT_EQ(s.samples().size(), 3u);
	EXPECT_EQ(s.samples()[0].keyframes, 25u);
	EXPECT_EQ(s.samples()[0].frames, 4u);
	EXPECT_EQ(s.samples()[1].keyframes, 51u);  // the first count at or past 50
	EXPECT_EQ(s.samples()[2].keyframes, 75u);
	EXPECT_DOUBLE_EQ(s.samples()[2].rssMb, 175.0);
	EXPECT_EQ(s.toJson(), "[[25, 4, 125.0], [51, 10, 151.0], [75, 13, 175.0]]");
}

TEST(ProcessMemory, RejectsAZeroStep) { EXPECT_THROW(MemorySampler(0), std::invalid_argument); }

TEST(StageTimings, BlockMeansFollowTheOrderOfTheSamples)
{
	keygrid::slam::StageTimings t;
	for (double x : {1.0, 3.0, 5.0, 7.0, 10.0}) t.add("track", x);
	const auto m = t.blockMeans("track", 2);
	ASSERT_EQ(m.size(), 3u);
	EXPECT_DOUBLE_EQ(m[0], 2.0);
	EXPECT_DOUBLE_EQ(m[1], 6.0);
	EXPECT_DOUBLE_EQ(m[2], 10.0);  // the shorter last block
	EXPECT_TRUE(t.blockMeans("absent", 2).empty());
	EXPECT_THROW(t.blockMeans("track", 0), std::invalid_argument);
}
