// keygrid-slam end to end: the shipped INI on real TUM frames (when ../shared/data is present),
// determinism, threaded mode, report contents and bad inputs.
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/slam/MetricMaps.h>
#include <keygrid/slam/SlamConfig.h>
#include <keygrid/slam/apps/SlamApp.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/system/filesystem.h>

#include "TestData.h"

#include <fstream>
#include <regex>

using namespace keygrid;

namespace
{
std::string rpy() { return test::sharedDataDir() + "/tum_fr1_rpy_first250"; }
}  // namespace

TEST(SlamApp, TracksRealFr1RpyFramesWithinAteBound)
{
	KEYGRID_SKIP_WITHOUT_SHARED_DATA("tum_fr1_rpy_first250");
	slam::SlamRunOptions o;
	o.configPath = test::sourceDir() + "/config/tum_fr1.ini";
	o.input = rpy();
	o.output = test::scratchDir("slam_rpy");
	o.groundTruth = rpy() + "/groundtruth.txt";
	o.maxFrames = 120;
	o.quiet = true;
	const auto r = slam::runSlam(o);
	EXPECT_TRUE(r.error.empty()) << r.error;
	EXPECT_EQ(r.frames, 120u);
	EXPECT_EQ(r.tracked, 120u) << "every frame must be tracked";
	ASSERT_TRUE(r.ateRmse.has_value());
	// Fast hand-held rotations with motion blur. An empirical regression margin, not the
	// accuracy target: the figure of these 120 frames is in doc/evaluation.md, "Trajectory
	// accuracy of the SfM frontend".
	EXPECT_LT(*r.ateRmse, 0.025);
	const auto traj = core::readTumTrajectory(o.output + "/trajectory.txt");
	EXPECT_EQ(traj.size(), 120u);
	const std::string js = test::readTextFile(o.output + "/report.json");
	EXPECT_EQ(test::jsonNumber(js, "frames"), 120);
	EXPECT_GT(test::jsonNumber(js, "keyframes"), 2);
	EXPECT_GT(test::jsonNumber(js, "landmarks"), 500);
	EXPECT_NEAR(test::jsonNumber(js, "ate_rmse_m"), *r.ateRmse, 1e-6);
	EXPECT_NE(js.find("\"median_ms\""), std::string::npos);
	EXPECT_NE(js.find("\"p95_ms\""), std::string::npos);
}

TEST(SlamApp, SequentialRunsAreIdenticalAndThreadedModeMatchesThem)
{
	KEYGRID_SKIP_WITHOUT_SHARED_DATA("tum_fr1_rpy_first250");
	// Threaded mode with [slam] mapping_lag = 0: tracking waits for local mapping.
	const std::string lockstep = test::scratchDir("slam_det_cfg") + "/lag0.ini";
	{
		std::ofstream f(lockstep);
		f << test::readTextFile(test::sourceDir() + "/config/tum_fr1.ini") << "\n[slam]\nmapping_lag = 0\n";
	}
	std::string outs[4];
	for (int i = 0; i < 4; i++)
	{
		slam::SlamRunOptions o;
		o.configPath = i == 2 ? lockstep : test::sourceDir() + "/config/tum_fr1.ini";
		o.input = rpy();
		o.output = test::scratchDir("slam_det" + std::to_string(i));
		o.maxFrames = 40;
		o.quiet = true;
		o.groundTruth = rpy() + "/groundtruth.txt";
		if (i >= 2) o.modeOverride = slam::RunMode::Threaded;  // run 3: the default mapping_lag = 1
		const auto r = slam::runSlam(o);
		EXPECT_TRUE(r.error.empty()) << r.error;
		EXPECT_EQ(r.tracked, 40u);
		ASSERT_TRUE(r.ateRmse.has_value());
		// 2 cm: the project's target on fr1_rpy (doc/evaluation.md, Summary), for every mode
		// and on these first frames too.
		EXPECT_LT(*r.ateRmse, 0.02) << "run " << i;
		outs[i] = test::readTextFile(o.output + "/trajectory.txt");
		EXPECT_EQ(core::readTumTrajectory(o.output + "/trajectory.txt").size(), 40u);
	}
	ASSERT_FALSE(outs[0].empty());
	EXPECT_EQ(outs[0], outs[1]) << "two sequential runs differ";
	// mapping_lag = 0: tracking waits for local mapping of each keyframe, so it sees the map
	// sequential mode sees; without a loop closure (asynchronous) the trajectories match.
	EXPECT_EQ(outs[0], outs[2]) << "threaded mode with mapping_lag 0 differs from sequential";
}

TEST(SlamApp, ConvertedRawlogGivesTheSameTrajectoryAsTheTumFolder)
{
	KEYGRID_SKIP_WITHOUT_SHARED_DATA("tum_fr1_desk_9frames");
	const std::string dir = test::scratchDir("slam_rawlog");
	const std::string desk = test::sharedDataDir() + "/tum_fr1_desk_9frames";
	std::string out;
	ASSERT_EQ(test::runCommand(test::toolPath("keygrid-tum2rawlog") + " --quiet --input " + desk + " --output " + dir + "/d.rawlog", &out), 0) << out;
	std::string traj[2];
	for (int i = 0; i < 2; i++)
	{
		slam::SlamRunOptions o;
		o.configPath = test::sourceDir() + "/config/tum_fr1.ini";
		o.input = i == 0 ? desk : dir + "/d.rawlog";
		o.output = dir + "/out" + std::to_string(i);
		o.quiet = true;
		const auto r = slam::runSlam(o);
		EXPECT_EQ(r.tracked, 9u);
		traj[i] = test::readTextFile(o.output + "/trajectory.txt");
	}
	// Depth is bit-exact through the rawlog, so the estimate is too (timestamps: 1 us rounding).
	EXPECT_EQ(traj[0], traj[1]);
}

TEST(SlamApp, BadInputsAreClearErrors)
{
	const std::string dir = test::scratchDir("slam_bad");
	const std::string tool = test::toolPath("keygrid-slam");
	std::string out;
	EXPECT_EQ(test::runCommand(tool + " --input x --output " + dir, &out), 2);
	EXPECT_NE(out.find("missing --config"), std::string::npos) << out;
	EXPECT_EQ(test::runCommand(tool + " --config /nonexistent.ini --input x --output " + dir, &out), 1);
	EXPECT_NE(out.find("does not exist"), std::string::npos) << out;
	std::ofstream(dir + "/bad.ini") << "[features]\nnum_features = 3\n";
	EXPECT_EQ(test::runCommand(tool + " --config " + dir + "/bad.ini --input x --output " + dir, &out), 1);
	EXPECT_NE(out.find("num_features = 3"), std::string::npos) << out;
	std::ofstream(dir + "/mode.ini") << "[slam]\nmode = turbo\n";
	EXPECT_EQ(test::runCommand(tool + " --config " + dir + "/mode.ini --input x --output " + dir, &out), 1);
	EXPECT_NE(out.find("turbo"), std::string::npos) << out;
	std::ofstream(dir + "/lag.ini") << "[slam]\nmode = threaded\nmapping_lag = 9\n";
	EXPECT_EQ(test::runCommand(tool + " --config " + dir + "/lag.ini --input x --output " + dir, &out), 1);
	EXPECT_NE(out.find("mapping_lag = 9"), std::string::npos) << out;
	EXPECT_EQ(test::runCommand(tool + " --config " + test::sourceDir() + "/config/tum_fr1.ini --input /nonexistent --output " + dir, &out), 1);
	EXPECT_NE(out.find("/nonexistent"), std::string::npos) << out;
	// A folder where a file belongs, values that are not what the key takes: named before any
	// frame is read.
	EXPECT_EQ(test::runCommand(tool + " --config " + dir + " --input x --output " + dir, &out), 1);
	EXPECT_NE(out.find("is a folder, not a file"), std::string::npos) << out;
	const std::string fr1 = " --config " + test::sourceDir() + "/config/tum_fr1.ini --input /nonexistent --output " + dir;
	EXPECT_EQ(test::runCommand(tool + fr1 + " --gt " + dir, &out), 1);
	EXPECT_NE(out.find("is a folder, not a file"), std::string::npos) << out;
	for (const char* v : {"99999999999", "1000abc", "1e3", "40.0.0", "forty"})
	{
		EXPECT_EQ(test::runCommand(tool + fr1 + " --set features.num_features=" + v, &out), 1) << v;
		EXPECT_NE(out.find(std::string("num_features = ")), std::string::npos) << out;
		EXPECT_NE(out.find(v), std::string::npos) << out;
	}
	EXPECT_EQ(test::runCommand(tool + fr1 + " --set features.pyramid_pixel_centres=maybe", &out), 1);
	EXPECT_NE(out.find("'maybe' is not a boolean"), std::string::npos) << out;
	// --dump-config output is itself a valid configuration.
	ASSERT_EQ(test::runCommand(tool + " --dump-config > " + dir + "/dump.ini"), 0);
	EXPECT_NO_THROW(slam::SlamConfig::FromFile(dir + "/dump.ini"));
}

TEST(SlamApp, RealKinectRawlogFrameInitialisesTheMap)
{
	const std::string rawlog = test::mrptDatasetsDir() + "/tests_rgbd.rawlog";
	if (!mrpt::system::fileExists(rawlog)) GTEST_SKIP() << "mrpt-common not installed";
	slam::SlamRunOptions o;
	o.configPath = test::sourceDir() + "/config/tum_fr1.ini";
	o.input = rawlog;
	// A nested output folder is created with its parents.
	o.output = test::scratchDir("slam_kinect") + "/runs/today";
	o.quiet = true;
	const auto r = slam::runSlam(o);
	EXPECT_TRUE(r.error.empty()) << r.error;
	EXPECT_EQ(r.frames, 1u);
	EXPECT_EQ(r.tracked, 1u);
	const std::string js = test::readTextFile(o.output + "/report.json");
	EXPECT_GT(test::jsonNumber(js, "landmarks"), 300);
}

TEST(SlamApp, UnknownKeysOfSlamSectionsAreNamedAndShippedConfigsAreClean)
{
	const std::string dir = test::scratchDir("slam_unknown_keys");
	for (const char* shipped : {"sim.ini", "tum_fr1.ini", "tum_fr2.ini", "tum_fr3.ini", "kinect_openni2.ini"})
		EXPECT_NO_THROW(slam::SlamConfig::FromFile(test::sourceDir() + "/config/" + shipped)) << shipped;
	for (const std::string bad : {"[tracker]\nradius_predicton = 5\n", "[hoc]\nenable = true\n", "[slam]\nmodes = threaded\n"})
	{
		const std::string path = dir + "/bad.ini";
		std::ofstream(path) << bad;
		const std::string key = bad.substr(bad.find('\n') + 1, bad.find(' ', bad.find('\n')) - bad.find('\n') - 1);
		try
		{
			slam::SlamConfig::FromFile(path);
			ADD_FAILURE() << "accepted " << bad;
		}
		catch (const std::invalid_argument& e)
		{
			EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
		}
	}
	// The map plugins' and the live camera's sections are left to their owners; any other
	// section is a typo, named (a misspelt [trackr] would be ignored with all its keys).
	std::ofstream(dir + "/other.ini") << "[MappingApplication]\npointsMap_count = 1\n[MappingApplication_pointsMap_00_insertOpts]\nminDistBetweenLaserPoints = 0.1\n[live_LEFT]\nx = 1\n";
	EXPECT_NO_THROW(slam::SlamConfig::FromFile(dir + "/other.ini"));
	std::ofstream(dir + "/typo.ini") << "[trackr]\nclose_depth = 3\n";
	try
	{
		slam::SlamConfig::FromFile(dir + "/typo.ini");
		ADD_FAILURE() << "accepted [trackr]";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("[trackr]: unknown section"), std::string::npos) << e.what();
	}
}

TEST(SlamApp, ConfigTextThatMrptWouldSkipIsAnError)
{
	// MRPT's reader skips lines it cannot parse: an unclosed section header, a stray word, a
	// binary file would all run with defaults.
	const std::string dir = test::scratchDir("slam_config_text");
	const std::string tool = test::toolPath("keygrid-slam");
	std::string out;
	std::ofstream(dir + "/unclosed.ini") << "[slam]\nmode = sequential\n[tracker\nclose_depth = 3\n";
	EXPECT_EQ(test::runCommand(tool + " --config " + dir + "/unclosed.ini --input x --output " + dir, &out), 1);
	EXPECT_NE(out.find("unclosed.ini:3: '[tracker' is not a [section] line"), std::string::npos) << out;
	std::ofstream(dir + "/stray.ini") << "# comment\n[slam]\nmode sequential\n";
	EXPECT_EQ(test::runCommand(tool + " --config " + dir + "/stray.ini --input x --output " + dir, &out), 1);
	EXPECT_NE(out.find("stray.ini:3: 'mode sequential' is not a [section], a key = value or a comment"), std::string::npos) << out;
	{
		std::ofstream bin(dir + "/binary.ini", std::ios::binary);
		const char bytes[] = {'\x7f', 'E', 'L', 'F', '\0', '\x01', '\n', 'x'};
		bin.write(bytes, sizeof(bytes));
	}
	EXPECT_EQ(test::runCommand(tool + " --config " + dir + "/binary.ini --input x --output " + dir, &out), 1);
	EXPECT_NE(out.find("not a text file"), std::string::npos) << out;
}

TEST(SlamApp, EveryValueMustBeOfItsDefaultsKind)
{
	// MRPT's readers would run with 0, 1000, 1 and false.
	const std::pair<const char*, const char*> bad[] = {
		{"[tracker]\nclose_depth = abc\n", "close_depth = 'abc' is not a finite number"},
		{"[tracker]\nclose_depth = inf\n", "close_depth = 'inf' is not a finite number"},
		{"[tracker]\nmin_inliers = 1000abc\n", "min_inliers = '1000abc' is not a whole number"},
		{"[tracker]\nmin_inliers = 1e3\n", "min_inliers = '1e3' is not a whole number"},
		{"[tracker]\nmin_inliers = 40.0.0\n", "min_inliers = '40.0.0' is not a whole number"},
		{"[loop_closing]\nenabled = maybe\n", "enabled = 'maybe' is not a boolean"}};
	for (const auto& [text, message] : bad)
	{
		try
		{
			slam::SlamConfig::FromConfig(mrpt::config::CConfigFileMemory(std::string(text)), "test.ini");
			ADD_FAILURE() << "accepted " << text;
		}
		catch (const std::invalid_argument& e)
		{
			EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
		}
	}
	// Each kind in its right form is accepted.
	EXPECT_NO_THROW(slam::SlamConfig::FromConfig(
		mrpt::config::CConfigFileMemory(std::string("[tracker]\nclose_depth = 2.5\nmin_inliers = 30\n[loop_closing]\nenabled = 0\n")), "ok.ini"));
}

TEST(SlamApp, MapSectionsThatNoMapReadsAreNamed)
{
	const auto errorOf = [](const std::string& text)
	{
		try
		{
			slam::MetricMaps maps(mrpt::config::CConfigFileMemory(text), {});
		}
		catch (const std::invalid_argument& e)
		{
			return std::string(e.what());
		}
		return std::string();
	};
	const std::string maps = "[MappingApplication]\nismOccupancyGrid2D_count = 1\n";
	EXPECT_EQ(errorOf(maps + "[MappingApplication_ismOccupancyGrid2D_00_insertOpts]\nmaxRange = 4\n"), "");
	EXPECT_NE(errorOf("[MappingApplication]\nismOccupancyGrid2D_count = one\n").find("ismOccupancyGrid2D_count = 'one' is not a whole number"), std::string::npos);
	EXPECT_NE(errorOf(maps + "[MappingApplication_ismOccupancyGrid2D_00_insertOpt]\nmaxRange = 4\n").find("unknown option group 'insertOpt'"), std::string::npos);
	// A map switched off keeps its options (count 0, or fewer maps than sections).
	EXPECT_EQ(errorOf(maps + "[MappingApplication_ismOccupancyGrid2D_01_insertOpts]\nmaxRange = 4\n"), "");
	EXPECT_EQ(errorOf("[MappingApplication]\nismOccupancyGrid2D_count = 0\n[MappingApplication_ismOccupancyGrid2D_00_insertOpts]\nmaxRange = 4\n"), "");
	EXPECT_NE(errorOf(maps + "[MappingApplication_ismOccupancyGrid_00_insertOpts]\nmaxRange = 4\n").find("no map type 'ismOccupancyGrid'"), std::string::npos);
	// A keygrid plugin's keys: a typo is named.
	EXPECT_NE(errorOf(maps + "[MappingApplication_ismOccupancyGrid2D_00_insertOpts]\nmaxRang = 4\n").find("maxRang: unknown key"), std::string::npos);
}

TEST(SlamApp, SetOverridesKeysLikeTheFileWouldAndRejectsUnknownOnes)
{
	const std::string dir = test::scratchDir("slam_set");
	const std::string tool = test::toolPath("keygrid-slam");
	const std::string base = test::sourceDir() + "/config/tum_fr1.ini";
	std::string out;
	// Misspelt keys and bad syntax are named, before any input is opened.
	EXPECT_EQ(test::runCommand(tool + " --config " + base + " --input x --output " + dir + " --set 'featurs.num_features=900'", &out), 1);
	EXPECT_NE(out.find("featurs.num_features"), std::string::npos) << out;
	EXPECT_EQ(test::runCommand(tool + " --config " + base + " --input x --output " + dir + " --set 'features.num_feature=900'", &out), 1);
	EXPECT_NE(out.find("features.num_feature"), std::string::npos) << out;
	EXPECT_EQ(test::runCommand(tool + " --config " + base + " --input x --output " + dir + " --set 'num_features=900'", &out), 2);
	EXPECT_NE(out.find("num_features=900"), std::string::npos) << out;
	// Values go through the same validation as the file's.
	EXPECT_EQ(test::runCommand(tool + " --config " + base + " --input x --output " + dir + " --set 'features.num_features=3'", &out), 1);
	EXPECT_NE(out.find("num_features = 3"), std::string::npos) << out;
	// --dump-config shows the result: a replaced key, and a key of a section the file lacks.
	ASSERT_EQ(test::runCommand(tool + " --config " + base + " --dump-config --set 'features.num_features=900; hoc.enabled=true' > " + dir + "/dump.ini", &out), 0) << out;
	const auto dumped = slam::SlamConfig::FromFile(dir + "/dump.ini");
	EXPECT_EQ(dumped.features.numFeatures, 900);
	EXPECT_TRUE(dumped.tracker.hoc.enabled);
	EXPECT_EQ(slam::SlamConfig::FromFile(base).features.numFeatures, 1000) << "the file itself is not modified";

	KEYGRID_SKIP_WITHOUT_SHARED_DATA("tum_fr1_desk_9frames");
	const std::string desk = test::sharedDataDir() + "/tum_fr1_desk_9frames";
	// The same run configured by --set and by a file holding the same keys: identical outputs.
	{
		std::string text = test::readTextFile(base);
		text = std::regex_replace(text, std::regex("num_features = 1000"), "num_features = 700");
		text = std::regex_replace(text, std::regex("\\[tracker\\]\n"), "[tracker]\nmin_inliers = 20\n");
		ASSERT_NE(text.find("num_features = 700"), std::string::npos);
		ASSERT_NE(text.find("min_inliers = 20"), std::string::npos);
		std::ofstream(dir + "/edited.ini") << text;
	}
	std::string traj[2];
	for (int i = 0; i < 2; i++)
	{
		slam::SlamRunOptions o;
		o.configPath = i == 0 ? dir + "/edited.ini" : base;
		if (i == 1) o.set = "features.num_features = 700; tracker.min_inliers=20";
		o.input = desk;
		o.output = dir + "/out" + std::to_string(i);
		o.quiet = true;
		EXPECT_EQ(slam::runSlam(o).tracked, 9u);
		traj[i] = test::readTextFile(o.output + "/trajectory.txt");
	}
	EXPECT_EQ(traj[0], traj[1]);
	EXPECT_NE(test::readTextFile(dir + "/out1/report.json").find("\"config_set\": \"features.num_features = 700; tracker.min_inliers=20\""), std::string::npos);
}
