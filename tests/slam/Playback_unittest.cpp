// [slam] playback_rate: recorded frames released at the pace of their timestamps, as a camera
// delivers them (slam::PlaybackSchedule), and what keygrid-slam reports of it.
#include <keygrid/slam/PlaybackSchedule.h>

#include "SimSlamRun.h"

#include <cmath>
#include <limits>
#include <regex>
#include <stdexcept>
#include <vector>

using namespace keygrid;

TEST(PlaybackSchedule, ReleasesFramesAtTheirTimestampsPaceTimesTheRate)
{
	// A repeated and a backward stamp (the frame loop drops those frames) add no time; a 30 s
	// gap (a paused recording) counts for kMaxGap.
	const std::vector<double> stamps = {100.0, 100.1, 100.25, 100.25, 100.2, 130.25, 130.3};
	const std::vector<double> atRate1 = {0.0, 0.1, 0.25, 0.25, 0.25, 1.25, 1.3};
	ASSERT_EQ(slam::PlaybackSchedule::kMaxGap, 1.0);
	for (const double rate : {1.0, 2.0, 0.5})
	{
		slam::PlaybackSchedule schedule(rate);
		for (std::size_t i = 0; i < stamps.size(); i++)
		{
			// The gaps divided by the rate, the 30 s one capped at 1 s after the division.
			const double expected = i < 5 ? atRate1[i] / rate : atRate1[4] / rate + 1.0 + (i == 6 ? 0.05 / rate : 0.0);
			EXPECT_NEAR(schedule.release(stamps[i]), expected, 1e-9) << "rate " << rate << ", frame " << i;
		}
	}
	for (const double bad : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()})
		EXPECT_THROW(slam::PlaybackSchedule{bad}, std::invalid_argument) << bad;
}

TEST(SlamApp, PacedPlaybackTakesTheRecordingsTimeAndChangesNoSequentialResult)
{
	const std::string dir = test::scratchDir("slam_playback");
	// keygrid-sim renders at 30 Hz; at a quarter of that pace the last frame is due
	// 23 / 7.5 s = 3.07 s after the first, about 4x what the unpaced run takes in a Release build.
	const int frames = 24;
	const double rate = 0.25;
	const auto unpaced = test::renderAndRunSlam(
		dir, "--scene " + test::dataDir() + "/sim/room_arc.ini --frames " + std::to_string(frames) +
				 " --voxel-resolution 0 --floorplan-resolution 0",
		false);
	ASSERT_TRUE(unpaced.rendered) << unpaced.simLog;
	ASSERT_TRUE(unpaced.result.error.empty()) << unpaced.result.error;
	auto o = unpaced.options;
	o.output = dir + "/paced";
	o.set = "slam.playback_rate=0.25";
	const auto paced = slam::runSlam(o);
	ASSERT_TRUE(paced.error.empty()) << paced.error;
	EXPECT_EQ(paced.frames, static_cast<std::size_t>(frames));

	// Pacing delays frames and nothing else: sequential mode gives the same trajectory.
	const std::string trajectory = test::readTextFile(unpaced.options.output + "/trajectory.txt");
	ASSERT_FALSE(trajectory.empty());
	EXPECT_EQ(test::readTextFile(o.output + "/trajectory.txt"), trajectory);

	const std::string js = test::readTextFile(o.output + "/report.json");
	EXPECT_EQ(test::jsonNumber(js, "playback_rate"), rate);
	// The last frame is due (frames - 1) / (30 rate) s after the first: a lower bound on the run.
	EXPECT_GE(test::jsonNumber(js, "wall_time_s"), (frames - 1) / (30.0 * rate) - 1e-3);
	std::smatch m;
	ASSERT_TRUE(std::regex_search(js, m, std::regex("\"frame_latency\": \\{\\s*\"count\": ([0-9]+)"))) << js;
	EXPECT_EQ(std::stoi(m[1].str()), frames) << "one latency per frame";

	const std::string unpacedJs = test::readTextFile(unpaced.options.output + "/report.json");
	EXPECT_EQ(test::jsonNumber(unpacedJs, "playback_rate"), 0.0);
	EXPECT_EQ(unpacedJs.find("frame_latency"), std::string::npos) << "no release time without pacing";
}
