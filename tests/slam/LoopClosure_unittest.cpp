// Loop closing's integration test: a generated loop through keygrid-slam closes the loop (reported
// with keyframe ids) and meets the accuracy bound; no loop is claimed on real data without one.
#include <keygrid/slam/apps/SlamApp.h>
#include <mrpt/system/filesystem.h>

#include "SimSlamRun.h"
#include "TestData.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>

using namespace keygrid;

TEST(LoopClosure, GeneratedRoomLoopIsClosed)
{
	// The room loop compressed to 10 s (0.66 m/s, 38 deg/s): the camera returns to its start.
	const auto run = test::renderAndRunSlam(
		test::scratchDir("loop_room"), "--frames 300 --scene " + test::sourceDir() + "/config/sim/room_loop.ini", true);
	// 1 cm: the target of the synthetic loops with loop closing (doc/evaluation.md, Summary).
	ASSERT_NO_FATAL_FAILURE(test::expectCentimetreRun(run, 300));
	const auto& o = run.options;
	const std::string js = test::readTextFile(o.output + "/report.json");
	const auto report = nlohmann::json::parse(js);
	ASSERT_FALSE(report["loop_closures"].empty()) << js;
	// Closed when the camera is back near its start: late frame, early keyframe.
	EXPECT_GT(report["loop_closures"][0]["frame"].get<int>(), 250);
	EXPECT_LT(report["loop_closures"][0]["loop_keyframe"].get<int>(), 5);
	EXPECT_TRUE(mrpt::system::fileExists(o.output + "/posegraph.g2o"));
	{
		// loop_queries.csv: one row per keyframe; the closing keyframe's row says "closed" and
		// names its candidate, every other row a reason.
		std::ifstream csv(o.output + "/loop_queries.csv");
		std::string line;
		ASSERT_TRUE(std::getline(csv, line));
		EXPECT_EQ(line.rfind("keyframe,frame,outcome,", 0), 0u) << line;
		int rows = 0, closed = 0;
		while (std::getline(csv, line))
		{
			rows++;
			std::smatch q;
			ASSERT_TRUE(std::regex_match(line, q, std::regex("(\\d+),(\\d+),([a-z_]+),([^,]*),(\\d+),(\\d*),([^,]*),(\\d*),.*"))) << line;
			if (q[3] != "closed") continue;
			closed++;
			const auto& loop = report["loop_closures"][0];
			EXPECT_EQ(q[1], std::to_string(loop["keyframe"].get<long long>())) << line;
			EXPECT_EQ(q[2], std::to_string(loop["frame"].get<long long>())) << line;
			EXPECT_EQ(q[8], std::to_string(loop["loop_keyframe"].get<long long>())) << "the verified candidate is the loop keyframe: " << line;
		}
		EXPECT_EQ(closed, 1);
		EXPECT_GE(rows, static_cast<int>(test::jsonNumber(js, "keyframes")));
	}

	// Threaded mode on the same frames: tracking, local mapping and loop closing (with the
	// 2D/3D maps of config/sim.ini) on their own threads; not bit-identical, same bounds.
	auto ot = o;
	ot.output = o.output + "_threaded";
	ot.modeOverride = slam::RunMode::Threaded;
	const auto rt = slam::runSlam(ot);
	ASSERT_NO_FATAL_FAILURE(test::expectCentimetreRun(rt, 300));
	const std::string jt = test::readTextFile(ot.output + "/report.json");
	const auto reportT = nlohmann::json::parse(jt);
	ASSERT_FALSE(reportT["loop_closures"].empty()) << jt;
	EXPECT_GT(reportT["loop_closures"][0]["frame"].get<int>(), 250);
	EXPECT_LT(reportT["loop_closures"][0]["loop_keyframe"].get<int>(), 5);
	EXPECT_NE(jt.find("\"ba_discarded\": "), std::string::npos);
	EXPECT_TRUE(mrpt::system::fileExists(ot.output + "/map_3d.bt"));
}

TEST(LoopClosure, NoLoopClaimedOnRealFramesWithoutOne)
{
	KEYGRID_SKIP_WITHOUT_SHARED_DATA("tum_fr1_rpy_first250");
	const auto o = test::shippedConfigRun("config/tum_fr1.ini", test::sharedDataDir() + "/tum_fr1_rpy_first250", test::scratchDir("loop_rpy"));
	const auto r = slam::runSlam(o);
	ASSERT_TRUE(r.error.empty()) << r.error;
	EXPECT_EQ(r.frames, 250u);
	const std::string js = test::readTextFile(o.output + "/report.json");
	EXPECT_TRUE(nlohmann::json::parse(js)["loop_closures"].empty()) << js;
}
