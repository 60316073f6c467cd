/** \file BatchApp_unittest.cpp
 * keygrid-batch: experiment parsing (every invalid key or value fails naming it), configuration
 * overrides, the results tables, and a real matrix (a generated sequence and a nonexistent one
 * x two configurations) whose ATE values must equal keygrid-eval's on the same trajectories.
 */
#include <keygrid/slam/SlamConfig.h>
#include <keygrid/slam/apps/BatchExperiment.h>
#include <keygrid/slam/apps/BatchResults.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "../TestData.h"

using namespace keygrid::slam;
using keygrid::test::dataDir;
using keygrid::test::sourceDir;

namespace
{
/** A valid experiment; `extra` is appended (more sections), `replace` swaps one line. */
std::string experiment(const std::string& extra = "", const std::string& line = "", const std::string& by = "")
{
	std::string s =
		"# test experiment\n"
		"[batch]\n"
		"output = /tmp/never_written\n"
		"jobs = 3\n"
		"repeats = 2\n"
		"title = A test\n"
		"timeout = 60\n"
		"\n"
		"[dataset.recorded]\n"
		"input = some/folder\n"
		"gt = some/folder/groundtruth.txt\n"
		"max_frames = 40\n"
		"\n"
		"[dataset.synthetic]\n"
		"scene = " +
		dataDir() + "/sim/room_arc.ini\n" +
		"seed = 7\n"
		"frames = 30\n"
		"set = sensor.disparity_distortion=0.1\n"
		"\n"
		"[config.base]\n"
		"file = " +
		sourceDir() + "/config/sim.ini\n" +
		"\n"
		"[config.no_loops]\n"
		"file = " +
		sourceDir() + "/config/sim.ini\n" +
		"set = loop_closing.enabled=false ; features.num_features = 500\n";
	if (!line.empty())
	{
		const auto p = s.find(line);
		EXPECT_NE(p, std::string::npos) << line;
		if (p != std::string::npos) s.replace(p, line.size(), by);
	}
	return s + extra;
}

std::string errorOf(const std::string& text)
{
	try
	{
		ExperimentSpec::FromText(text, "exp.ini");
	}
	catch (const std::invalid_argument& e)
	{
		return e.what();
	}
	return "(no error)";
}

std::vector<std::vector<std::string>> readCsv(const std::string& path)
{
	std::vector<std::vector<std::string>> rows;
	std::istringstream in(keygrid::test::readTextFile(path));
	for (std::string line; std::getline(in, line);)
	{
		std::vector<std::string> cells;
		std::string cell;
		bool quoted = false;
		for (char c : line)
		{
			if (c == '"')
				quoted = !quoted;
			else if (c == ',' && !quoted)
			{
				cells.push_back(cell);
				cell.clear();
			}
			else
				cell += c;
		}
		cells.push_back(cell);
		rows.push_back(cells);
	}
	return rows;
}
}  // namespace

TEST(BatchExperiment, ParsesValidFile)
{
	const auto spec = ExperimentSpec::FromText(experiment(), "exp.ini");
	EXPECT_EQ(spec.batch.output, "/tmp/never_written");
	EXPECT_EQ(spec.batch.jobs, 3);
	EXPECT_EQ(spec.batch.repeats, 2);
	EXPECT_EQ(spec.batch.title, "A test");
	EXPECT_DOUBLE_EQ(spec.batch.timeoutSeconds, 60.0);
	ASSERT_EQ(spec.datasets.size(), 2u);
	EXPECT_EQ(spec.datasets[0].name, "recorded");
	EXPECT_FALSE(spec.datasets[0].generated());
	EXPECT_EQ(spec.datasets[0].input, "some/folder");
	EXPECT_EQ(spec.datasets[0].gt, "some/folder/groundtruth.txt");
	EXPECT_EQ(spec.datasets[0].maxFrames, 40);
	EXPECT_EQ(spec.datasets[1].name, "synthetic");
	EXPECT_TRUE(spec.datasets[1].generated());
	EXPECT_EQ(spec.datasets[1].seed.value_or(-1), 7);
	EXPECT_EQ(spec.datasets[1].frames.value_or(-1), 30);
	EXPECT_EQ(spec.datasets[1].simSet, "sensor.disparity_distortion=0.1");
	EXPECT_TRUE(spec.datasets[0].simSet.empty());
	ASSERT_EQ(spec.configs.size(), 2u);
	EXPECT_EQ(spec.configs[0].name, "base");
	EXPECT_TRUE(spec.configs[0].overrides.empty());
	ASSERT_EQ(spec.configs[1].overrides.size(), 2u);
	EXPECT_EQ(spec.configs[1].overrides[0].section, "loop_closing");
	EXPECT_EQ(spec.configs[1].overrides[0].key, "enabled");
	EXPECT_EQ(spec.configs[1].overrides[0].value, "false");
	EXPECT_EQ(spec.configs[1].overrides[1].section, "features");
	EXPECT_EQ(spec.configs[1].overrides[1].key, "num_features");
	EXPECT_EQ(spec.configs[1].overrides[1].value, "500");
}

TEST(BatchExperiment, EveryInvalidKeyOrValueFailsNamingIt)
{
	struct Case
	{
		std::string line, by, extra, mustName;
	};
	const std::vector<Case> cases{
		{"jobs = 3", "jobs = 0", "", "jobs"},
		{"jobs = 3", "jobs = two", "", "jobs"},
		{"repeats = 2", "repeats = 1.5", "", "repeats"},
		{"timeout = 60", "timeout = -1", "", "timeout"},
		{"title = A test", "titel = A test", "", "titel"},
		{"max_frames = 40", "max_frames = -3", "", "max_frames"},
		{"seed = 7", "seed = x", "", "seed"},
		{"frames = 30", "frames = 0", "", "frames"},
		{"gt = some/folder/groundtruth.txt", "groundtruth = x", "", "groundtruth"},
		{"input = some/folder", "input = some/folder\nscene = x.ini", "", "[dataset.recorded]"},
		{"input = some/folder", "", "", "[dataset.recorded]"},
		{"max_frames = 40", "seed = 3", "", "seed"},
		{"max_frames = 40", "set = sensor.noise=false", "", "set"},
		{"set = sensor.disparity_distortion=0.1", "set = sensor.noise", "", "sensor.noise"},
		{"/sim/room_arc.ini", "/sim/no_such_scene.ini", "", "no_such_scene.ini"},
		{"set = loop_closing.enabled=false ;", "set = loop_closing.enabled ;", "", "loop_closing.enabled"},
		{"set = loop_closing.enabled=false ;", "set = enabled=false ;", "", "enabled=false"},
		{"[config.base]", "[configuration.base]", "", "[configuration.base]"},
		{"[dataset.recorded]", "[dataset._recorded]", "", "[dataset._recorded]"},
		{"jobs = 3", "jobs = 3\njobs = 4", "", "jobs appears twice"},
		{"", "", "\n[config.extra]\nset = slam.mode=threaded\n", "[config.extra]"},
		{"", "", "\n[config.missing_file]\nfile = /no/such/file.ini\n", "/no/such/file.ini"},
		{"", "", "\n[dataset.recorded]\ninput = x\n", "[dataset.recorded] appears twice"},
		{"", "", "\nstray line\n", "stray line"},
	};
	for (const auto& c : cases)
	{
		const std::string text = c.line.empty() ? experiment(c.extra) : experiment(c.extra, c.line, c.by);
		const std::string err = errorOf(text);
		EXPECT_NE(err.find(c.mustName), std::string::npos) << "case '" << c.by << c.extra << "' -> " << err;
		EXPECT_EQ(err.rfind("exp.ini:", 0), 0u) << err;  // names the file
	}
	// Whole sections missing.
	EXPECT_NE(errorOf("[dataset.a]\ninput = x\n[config.b]\nfile = " + sourceDir() + "/config/sim.ini\n").find("[batch]"), std::string::npos);
	EXPECT_NE(errorOf("[batch]\noutput = x\n[config.b]\nfile = " + sourceDir() + "/config/sim.ini\n").find("[dataset.NAME]"), std::string::npos);
	EXPECT_NE(errorOf("[batch]\noutput = x\n[dataset.a]\ninput = x\n").find("[config.NAME]"), std::string::npos);
}

TEST(BatchExperiment, AppliesOverridesToACopy)
{
	const std::string ini =
		"# header comment\n"
		"[slam]\n"
		"# mode comment\n"
		"Mode = sequential\n"
		"camera = auto\n"
		"\n"
		"[loop_closing]\n"
		"; the key below is replaced, this comment stays\n"
		"enabled = true\n"
		"\n"
		"[features]\n"
		"type = orb\n";
	const auto overrides = parseOverrides(
		"slam.mode=threaded; loop_closing.min_inliers = 55; features.num_features=321; tracker.bf=100; "
		"MappingApplication_ismOccupancyGrid2D_00_creationOpts.resolution=0.1",
		"set");
	const std::string out = applyOverrides(ini, overrides);
	// Replaced in place (case-insensitive key match), comments kept, other keys untouched.
	EXPECT_NE(out.find("# mode comment\nmode = threaded\ncamera = auto\n"), std::string::npos) << out;
	EXPECT_NE(out.find("; the key below is replaced, this comment stays\nenabled = true\nmin_inliers = 55\n"), std::string::npos) << out;
	EXPECT_NE(out.find("type = orb\nnum_features = 321\n"), std::string::npos) << out;
	EXPECT_EQ(out.find("sequential"), std::string::npos);
	// What MRPT's reader (as keygrid-slam) sees in the copy.
	mrpt::config::CConfigFileMemory mem(out);
	SlamConfig cfg;
	cfg.loadFromConfigFile(mem);
	EXPECT_EQ(cfg.mode, RunMode::Threaded);
	EXPECT_EQ(cfg.loop.ransac.minInliers, 55);
	EXPECT_TRUE(cfg.loop.enabled);
	EXPECT_EQ(cfg.features.numFeatures, 321);
	EXPECT_DOUBLE_EQ(cfg.tracker.pose.bf, 100.0);
	EXPECT_DOUBLE_EQ(mem.read_double("MappingApplication_ismOccupancyGrid2D_00_creationOpts", "resolution", 0), 0.1);
	// Applying the same overrides again changes nothing.
	EXPECT_EQ(applyOverrides(out, overrides), out);
}

TEST(BatchExperiment, UnknownOverrideKeysAreRejected)
{
	const std::string ini = keygrid::test::readTextFile(sourceDir() + "/config/sim.ini");
	ASSERT_FALSE(ini.empty());
	auto check = [&](const std::string& set) { checkOverrideKeys(ini, parseOverrides(set, "set"), "[config.x] set"); };
	EXPECT_NO_THROW(check("loop_closing.enabled=false"));      // a default key
	EXPECT_NO_THROW(check("maps.ism2d_input=dense"));          // in the file
	EXPECT_NO_THROW(check("MappingApplication.ismOccupancyGrid2D_count=0"));
	EXPECT_NO_THROW(check("MappingApplication_submappedOccupancyGrid3D_00_insertOpts.morphThreads=1"));
	EXPECT_NO_THROW(check("MappingApplication_ismOccupancyGrid2D_01_creationOpts.resolution=0.1"));
	for (const std::string bad :
		 {"loop_closing.enabeld", "slam.modes", "MappingApplication.noSuchMap_count",
		  "MappingApplication_ismOccupancyGrid2D_00_creationOpts.resolutoin", "nosection.mode"})
	{
		try
		{
			check(bad + "=1");
			ADD_FAILURE() << bad << " accepted";
		}
		catch (const std::invalid_argument& e)
		{
			EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
			EXPECT_NE(std::string(e.what()).find("[config.x]"), std::string::npos) << e.what();
		}
	}
}

TEST(BatchResults, MediansOverRepeatsAndFailedRuns)
{
	EXPECT_DOUBLE_EQ(*medianOf({3.0, 1.0, 2.0}), 2.0);
	EXPECT_DOUBLE_EQ(*medianOf({4.0, 1.0, 3.0, 2.0}), 2.5);
	EXPECT_DOUBLE_EQ(*medianOf({std::nullopt, 5.0, std::nullopt}), 5.0);
	EXPECT_FALSE(medianOf({std::nullopt}).has_value());

	auto run = [](const std::string& d, const std::string& c, double ate, double fps, const std::string& err = "") {
		RunMetrics m;
		m.dataset = d;
		m.config = c;
		m.ateRmse = ate;
		m.fps = fps;
		m.frames = 100;
		m.loopClosures = 1;
		m.error = err;
		return m;
	};
	const std::vector<RunMetrics> runs{
		run("b", "x", 0.02, 10), run("a", "x", 0.01, 30), run("b", "x", 0.04, 20), run("b", "x", 9.0, 1, "boom"),
		run("a", "y", 0.5, 1, "bad input"), run("b", "x", 0.03, 40)};
	const auto rows = aggregateRuns(runs);
	ASSERT_EQ(rows.size(), 3u);
	EXPECT_EQ(rows[0].dataset + "/" + rows[0].config, "b/x");  // first appearance order
	EXPECT_EQ(rows[0].runs, 4);
	EXPECT_EQ(rows[0].failed, 1);
	EXPECT_DOUBLE_EQ(*rows[0].ateRmse, 0.03);  // median of the successful 0.02, 0.04, 0.03
	EXPECT_DOUBLE_EQ(*rows[0].fps, 20.0);
	EXPECT_EQ(rows[0].error, "1 of 4 runs failed: boom");
	EXPECT_EQ(rows[1].failed, 0);
	EXPECT_TRUE(rows[1].error.empty());
	EXPECT_EQ(rows[2].dataset + "/" + rows[2].config, "a/y");
	EXPECT_EQ(rows[2].error, "bad input");
	EXPECT_DOUBLE_EQ(*rows[2].ateRmse, 0.5);  // no run succeeded: what the failed one reported

	const auto csv = resultsCsv(rows);
	EXPECT_NE(csv.find("b,x,4,1,100,,20.000,0.03,,,1,1 of 4 runs failed: boom\n"), std::string::npos) << csv;
	const auto md = resultsMarkdown(rows);
	EXPECT_NE(md.find("| b | x | 3/4 | 100 |  | 20.0 | 3.00 |  |  | 1 | 1 of 4 runs failed: boom |"), std::string::npos) << md;
}

TEST(BatchResults, ReadsSlamReport)
{
	const std::string dir = keygrid::test::scratchDir("batch_report");
	const std::string path = dir + "/report.json";
	std::ofstream(path) << "{\n  \"input\": \"a \\\"quoted\\\" path\",\n  \"frames\": 250,\n  \"tracked\": 248,\n"
						   "  \"keyframes\": 43,\n  \"landmarks\": 5120,\n  \"hoc\": {\"landmarks_pruned\": 3, \"x\": [1, 2]},\n"
						   "  \"loop_closures\": [{\"frame\": 434, \"score\": 0.5}, {\"frame\": 440, \"score\": 1e-3}],\n"
						   "  \"maps\": [], \"fps\": 24.125, \"timings\": {\"load\": {\"median_ms\": 1.5}},\n"
						   "  \"ate_rmse_m\": 0.0303, \"ok\": true, \"error\": null\n}\n";
	const RunMetrics m = readRunReport(path);
	EXPECT_TRUE(m.ok());
	EXPECT_EQ(*m.frames, 250);
	EXPECT_EQ(*m.tracked, 248);
	EXPECT_EQ(*m.keyframes, 43);
	EXPECT_EQ(*m.landmarks, 5120);
	EXPECT_EQ(*m.loopClosures, 2);
	EXPECT_DOUBLE_EQ(*m.fps, 24.125);
	EXPECT_DOUBLE_EQ(*m.ateRmse, 0.0303);

	std::ofstream(path) << "{\"frames\": 3, \"loop_closures\": [], \"error\": \"input.rawlog: truncated\"}";
	const RunMetrics f = readRunReport(path);
	EXPECT_EQ(f.error, "input.rawlog: truncated");
	EXPECT_EQ(*f.loopClosures, 0);
	EXPECT_FALSE(f.ateRmse.has_value());

	std::ofstream(path) << "{\"frames\": 3, ";
	EXPECT_THROW(readRunReport(path), std::runtime_error);
	EXPECT_THROW(readRunReport(dir + "/missing.json"), std::runtime_error);
}

// The real thing: keygrid-batch generates a 30-frame sequence with keygrid-sim and runs it, and
// a nonexistent recording, with two configurations.
TEST(BatchApp, RunsMatrixAndReportsAteAsKeygridEval)
{
	const std::string out = keygrid::test::scratchDir("batch_matrix");
	const std::string expPath = out + "/experiment.ini";
	std::ofstream(expPath) << "[batch]\noutput = " << out << "/results\njobs = 2\n\n"
						   << "[dataset.arc]\nscene = " << dataDir() << "/sim/room_arc.ini\nframes = 30\n"
						   << "set = sensor.image_noise_sigma=1.5\n\n"
						   << "[dataset.missing]\ninput = " << out << "/no_such_sequence.rawlog\n\n"
						   << "[config.default]\nfile = " << sourceDir() << "/config/sim.ini\n\n"
						   << "[config.fewer_features]\nfile = " << sourceDir() << "/config/sim.ini\n"
						   << "set = features.num_features=600; loop_closing.enabled=false\n";
	std::string log;
	const int rc = keygrid::test::runCommand(keygrid::test::toolPath("keygrid-batch") + " " + expPath, &log);
	EXPECT_EQ(rc, 1) << log;  // the missing dataset's runs failed, the table is still written
	EXPECT_NE(log.find("4 of 4 runs done"), std::string::npos) << log;

	const auto csv = readCsv(out + "/results/results.csv");
	ASSERT_EQ(csv.size(), 5u) << log;
	const std::vector<std::string> header{"dataset", "config", "runs", "failed", "frames", "tracked", "fps", "ate_rmse_m",
										  "keyframes", "landmarks", "loop_closures", "error"};
	EXPECT_EQ(csv[0], header);
	const std::vector<std::pair<std::string, std::string>> expected{
		{"arc", "default"}, {"arc", "fewer_features"}, {"missing", "default"}, {"missing", "fewer_features"}};
	for (std::size_t i = 0; i < expected.size(); i++)
	{
		const auto& row = csv[i + 1];
		ASSERT_EQ(row.size(), header.size());
		EXPECT_EQ(row[0], expected[i].first);
		EXPECT_EQ(row[1], expected[i].second);
		const std::string runDir = out + "/results/" + row[0] + "/" + row[1];
		if (row[0] == "missing")
		{
			EXPECT_EQ(row[3], "1");
			EXPECT_NE(row[11].find("no_such_sequence.rawlog"), std::string::npos) << row[11];
			EXPECT_EQ(row[7], "");
			continue;
		}
		EXPECT_EQ(row[3], "0") << row[11];
		EXPECT_EQ(row[11], "");
		EXPECT_EQ(row[4], "30");
		EXPECT_LE(std::stod(row[5]), 30.0);
		EXPECT_GT(std::stod(row[8]), 0.0);
		// Independent check of the ATE column: keygrid-eval on the run's trajectory.
		const std::string evalJson = runDir + "/eval.json";
		ASSERT_EQ(keygrid::test::runCommand(
					  keygrid::test::toolPath("keygrid-eval") + " --gt " + out + "/results/_datasets/arc/groundtruth.txt --est " +
					  runDir + "/trajectory.txt --json " + evalJson),
				  0);
		const double ateEval = keygrid::test::jsonNumber(keygrid::test::readTextFile(evalJson), "ate_rmse_m");
		EXPECT_NEAR(std::stod(row[7]), ateEval, 1e-8 + 1e-6 * ateEval);
		EXPECT_LT(ateEval, 0.05);  // a sane run, not an empty trajectory
	}
	// The overrides reached the run: its configuration copy loads with them.
	const SlamConfig applied = SlamConfig::FromFile(out + "/results/_configs/fewer_features.ini");
	EXPECT_EQ(applied.features.numFeatures, 600);
	EXPECT_FALSE(applied.loop.enabled);
	EXPECT_TRUE(SlamConfig::FromFile(out + "/results/_configs/default.ini").loop.enabled);
	EXPECT_NE(keygrid::test::readTextFile(out + "/results/results.md").find("| arc | default | 1/1 | 30 |"), std::string::npos);
	EXPECT_EQ(readCsv(out + "/results/runs.csv").size(), 5u);
	// The dataset's scene overrides went to keygrid-sim.
	EXPECT_NE(keygrid::test::readTextFile(out + "/results/results.md").find("--frames 30 --set 'sensor.image_noise_sigma=1.5'`"), std::string::npos);
}

TEST(BatchApp, BadCommandLinesAndSpecsFailWithOneLine)
{
	const std::string tool = keygrid::test::toolPath("keygrid-batch");
	std::string log;
	EXPECT_EQ(keygrid::test::runCommand(tool, &log), 2) << log;
	EXPECT_NE(log.find("expected one EXPERIMENT.ini"), std::string::npos) << log;
	EXPECT_EQ(keygrid::test::runCommand(tool + " /no/such/experiment.ini", &log), 1) << log;
	EXPECT_NE(log.find("/no/such/experiment.ini"), std::string::npos) << log;

	const std::string dir = keygrid::test::scratchDir("batch_badspec");
	std::ofstream(dir + "/e.ini") << "[batch]\noutput = " << dir << "/out\n[dataset.d]\ninput = x\n[config.c]\nfile = "
								  << sourceDir() << "/config/sim.ini\nset = loop_closing.enabeld=false\n";
	EXPECT_EQ(keygrid::test::runCommand(tool + " " + dir + "/e.ini", &log), 1) << log;
	EXPECT_NE(log.find("loop_closing.enabeld"), std::string::npos) << log;
	std::ofstream(dir + "/e.ini") << "[batch]\noutput = " << dir << "/out\n[dataset.d]\ninput = x\n[config.c]\nfile = "
								  << sourceDir() << "/config/sim.ini\nset = loop_closing.min_inliers=-4\n";
	EXPECT_EQ(keygrid::test::runCommand(tool + " " + dir + "/e.ini", &log), 1) << log;
	EXPECT_NE(log.find("min_inliers"), std::string::npos) << log;
	EXPECT_NE(log.find("[config.c]"), std::string::npos) << log;
}
