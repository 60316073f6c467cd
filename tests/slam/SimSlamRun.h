#pragma once
/** \file SimSlamRun.h
 * The integration tests' common step: keygrid-sim renders a scene into DIR/seq, and
 * keygrid-slam runs a shipped INI (config/sim.ini unless told) on its rawlog into DIR/out;
 * shippedConfigRun() is that run alone, on any input. */
#include <keygrid/slam/apps/SlamApp.h>

#include "TestData.h"

#include <string>

namespace keygrid::test
{
struct SimSlamRun
{
	bool rendered{false};      //!< keygrid-sim exited 0 (else nothing ran)
	std::string simLog;        //!< keygrid-sim's output
	slam::SlamRunOptions options;
	slam::SlamRunResult result;
};

/** A quiet keygrid-slam run of the shipped INI `config` (relative to the source folder) on
 * `input` into `output`. */
inline slam::SlamRunOptions shippedConfigRun(const std::string& config, const std::string& input, const std::string& output)
{
	slam::SlamRunOptions o;
	o.configPath = sourceDir() + "/" + config;
	o.input = input;
	o.output = output;
	o.quiet = true;
	return o;
}

/** `simArgs` are keygrid-sim's arguments besides --quiet and --output (e.g. "--scene X.ini
 * --frames 40"); `withGroundTruth` passes DIR/seq/groundtruth.txt as --gt; `config` is the
 * shipped INI to run, relative to the source folder. */
inline SimSlamRun renderAndRunSlam(
	const std::string& dir, const std::string& simArgs, bool withGroundTruth, const std::string& config = "config/sim.ini")
{
	SimSlamRun run;
	run.rendered =
		runCommand(toolPath("keygrid-sim") + " --quiet " + simArgs + " --output " + dir + "/seq", &run.simLog) == 0;
	if (!run.rendered) return run;
	run.options = shippedConfigRun(config, dir + "/seq/sequence.rawlog", dir + "/out");
	if (withGroundTruth) run.options.groundTruth = dir + "/seq/groundtruth.txt";
	run.result = slam::runSlam(run.options);
	return run;
}

/** The synthetic sequences' target with exact ground truth (doc/evaluation.md, Summary): the
 * run ended without error, tracked all of its `frames` frames and its ATE is under 1 cm. */
inline void expectCentimetreRun(const slam::SlamRunResult& r, std::size_t frames)
{
	EXPECT_TRUE(r.error.empty()) << r.error;
	EXPECT_EQ(r.frames, frames);
	EXPECT_EQ(r.tracked, frames);
	ASSERT_TRUE(r.ateRmse.has_value());
	EXPECT_LT(*r.ateRmse, 0.01);
}

/** expectCentimetreRun after checking that keygrid-sim rendered the sequence. */
inline void expectCentimetreRun(const SimSlamRun& run, std::size_t frames)
{
	ASSERT_TRUE(run.rendered) << run.simLog;
	expectCentimetreRun(run.result, frames);
}
}  // namespace keygrid::test
