/** \file EnumNames_unittest.cpp
 * The words keygrid-slam writes for its enums (frames.csv "method", loop_queries.csv
 * "outcome", report.json "mode") and reads back ([slam] mode, --mode): scripts and old
 * outputs depend on them, so they are pinned here.
 */
#include <keygrid/loop/LoopCloser.h>
#include <keygrid/sfm/Tracker.h>
#include <keygrid/slam/SlamConfig.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

using namespace keygrid;

TEST(EnumNames, TrackingMethodsAreTheWordsOfFramesCsv)
{
	using sfm::TrackingMethod;
	EXPECT_STREQ(sfm::toString(TrackingMethod::Init), "init");
	EXPECT_STREQ(sfm::toString(TrackingMethod::Prediction), "prediction");
	EXPECT_STREQ(sfm::toString(TrackingMethod::Pnp), "pnp");
	EXPECT_STREQ(sfm::toString(TrackingMethod::Relocalization), "relocalization");
	EXPECT_STREQ(sfm::toString(TrackingMethod::Lost), "lost");
}

TEST(EnumNames, LoopQueryOutcomesAreTheWordsOfLoopQueriesCsv)
{
	using loop::LoopQueryOutcome;
	EXPECT_STREQ(loop::toString(LoopQueryOutcome::Closed), "closed");
	EXPECT_STREQ(loop::toString(LoopQueryOutcome::NoVocabulary), "no_vocabulary");
	EXPECT_STREQ(loop::toString(LoopQueryOutcome::AfterLoop), "after_loop");
	EXPECT_STREQ(loop::toString(LoopQueryOutcome::NoCandidate), "no_candidate");
	EXPECT_STREQ(loop::toString(LoopQueryOutcome::NotConsistent), "not_consistent");
	EXPECT_STREQ(loop::toString(LoopQueryOutcome::FewMatches), "few_matches");
	EXPECT_STREQ(loop::toString(LoopQueryOutcome::RansacFailed), "ransac_failed");
	EXPECT_STREQ(loop::toString(LoopQueryOutcome::ProjectionFailed), "projection_failed");
	EXPECT_STREQ(loop::toString(LoopQueryOutcome::Implausible), "implausible");
	EXPECT_STREQ(loop::toString(LoopQueryOutcome::MergePending), "merge_pending");
	EXPECT_STREQ(loop::toString(LoopQueryOutcome::MergeSeenThrough), "merge_seen_through");
	EXPECT_STREQ(loop::toString(LoopQueryOutcome::PoseGraphFailed), "pose_graph_failed");
}

TEST(EnumNames, RunModeIsReadAndWrittenAsSequentialOrThreaded)
{
	using slam::RunMode;
	for (const RunMode m : {RunMode::Sequential, RunMode::Threaded})
		EXPECT_EQ(slam::runModeFromString(slam::toString(m), "mode"), m) << slam::toString(m);
	EXPECT_STREQ(slam::toString(RunMode::Sequential), "sequential");
	EXPECT_STREQ(slam::toString(RunMode::Threaded), "threaded");
	EXPECT_EQ(slam::SlamConfig().mode, RunMode::Sequential);

	mrpt::config::CConfigFileMemory threaded("[slam]\nmode = threaded\n");
	slam::SlamConfig cfg;
	cfg.loadFromConfigFile(threaded);
	EXPECT_EQ(cfg.mode, RunMode::Threaded);
	mrpt::config::CConfigFileMemory written;
	cfg.saveToConfigFile(written);
	const mrpt::config::CConfigFileMemory reread(written.getContent());
	EXPECT_EQ(reread.read_string("slam", "mode", ""), "threaded") << written.getContent();

	// Exact words only; the error names the key and the value.
	for (const char* bad : {"Threaded", "parallel"})
	{
		mrpt::config::CConfigFileMemory ini(std::string("[slam]\nmode = ") + bad + "\n");
		try
		{
			slam::SlamConfig c;
			c.loadFromConfigFile(ini);
			ADD_FAILURE() << "accepted mode '" << bad << "'";
		}
		catch (const std::invalid_argument& e)
		{
			EXPECT_EQ(std::string(e.what()), std::string("[slam] mode = '") + bad + "' (expected sequential or threaded)");
		}
	}
	EXPECT_THROW(slam::runModeFromString("threaded ", "mode"), std::invalid_argument);
}

TEST(EnumNames, SensorsAreTheWordsOfTheSlamSection)
{
	using slam::Sensor;
	EXPECT_STREQ(slam::toString(Sensor::Rgbd), "rgbd");
	EXPECT_STREQ(slam::toString(Sensor::Monocular), "monocular");
	EXPECT_EQ(slam::SlamConfig().sensor, Sensor::Rgbd);
	EXPECT_FALSE(slam::SlamConfig().tracker.monocular);

	// Monocular: the tracker's mode follows, and the two-view map is adjusted with [mapping]'s
	// bundle adjustment options.
	mrpt::config::CConfigFileMemory mono("[slam]\nsensor = monocular\n[mapping]\nfunction_tolerance = 1e-5\n[monocular]\ninit_max_frames = 7\n");
	slam::SlamConfig cfg;
	cfg.loadFromConfigFile(mono);
	EXPECT_EQ(cfg.sensor, Sensor::Monocular);
	EXPECT_TRUE(cfg.tracker.monocular);
	EXPECT_EQ(cfg.tracker.mono.initMaxFrames, 7);
	EXPECT_EQ(cfg.tracker.mono.ba.functionTolerance, 1e-5);
	mrpt::config::CConfigFileMemory written;
	cfg.saveToConfigFile(written);
	const mrpt::config::CConfigFileMemory reread(written.getContent());
	EXPECT_EQ(reread.read_string("slam", "sensor", ""), "monocular") << written.getContent();
	EXPECT_EQ(reread.read_int("monocular", "init_max_frames", 0), 7) << written.getContent();

	// Exact words only; the error names the key and the value.
	for (const char* bad : {"Monocular", "stereo"})
	{
		mrpt::config::CConfigFileMemory ini(std::string("[slam]\nsensor = ") + bad + "\n");
		slam::SlamConfig c;
		try
		{
			c.loadFromConfigFile(ini);
			ADD_FAILURE() << "accepted sensor '" << bad << "'";
		}
		catch (const std::invalid_argument& e)
		{
			EXPECT_NE(std::string(e.what()).find(std::string("[slam] sensor = '") + bad + "'"), std::string::npos) << e.what();
		}
	}
	// An invalid [monocular] value names its key.
	mrpt::config::CConfigFileMemory badRatio("[monocular]\nkeyframe_tracked_ratio = 1.5\n");
	slam::SlamConfig c;
	try
	{
		c.loadFromConfigFile(badRatio);
		ADD_FAILURE() << "accepted keyframe_tracked_ratio = 1.5";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("[monocular] keyframe_tracked_ratio"), std::string::npos) << e.what();
	}
}
