/** \file InputChecks_unittest.cpp
 * keygrid-slam on inputs that are not what it needs: a rawlog with no entry, one with only a
 * laser scanner's observations (a run with no frame is an error saying why), and frames whose
 * timestamps are missing, repeated or go backwards (skipped and counted: the trajectory's
 * stamps always increase).
 */
#include <keygrid/core/Frame.h>
#include <keygrid/core/RawlogWriter.h>
#include <keygrid/core/RgbdObservation.h>
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/slam/apps/SlamApp.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <opencv2/core.hpp>

#include <fstream>
#include <string>
#include <vector>

#include "TestData.h"

using namespace keygrid;

namespace
{
slam::SlamRunResult runOn(const std::string& input, const std::string& output)
{
	slam::SlamRunOptions o;
	o.configPath = test::sourceDir() + "/config/tum_fr1.ini";
	o.input = input;
	o.output = output;
	o.quiet = true;
	return slam::runSlam(o);
}

core::Frame texturedFrame(double t)
{
	core::Frame f;
	f.camera = core::RgbdCamera::FromPresetOrFile("kinect");
	f.timestamp = t;
	f.grey = cv::Mat(f.camera.height, f.camera.width, CV_8UC1);
	cv::theRNG().state = 7;  // the same texture in every frame: a camera standing still
	cv::randu(f.grey, 0, 256);
	f.depthRaw = cv::Mat(f.camera.height, f.camera.width, CV_16UC1, cv::Scalar(10000));
	return f;
}
}  // namespace

TEST(InputChecks, ARawlogWithoutRgbdEntriesIsAnErrorThatSaysWhy)
{
	const std::string dir = test::scratchDir("input_checks_empty");
	{
		core::RawlogWriter w(dir + "/empty.rawlog");
		w.close();
	}
	const auto empty = runOn(dir + "/empty.rawlog", dir + "/out_empty");
	EXPECT_EQ(empty.frames, 0u);
	EXPECT_NE(empty.error.find("no RGB-D frame in the input"), std::string::npos) << empty.error;

	{
		core::RawlogWriter w(dir + "/laser.rawlog");
		for (int i = 0; i < 3; i++) w.write(mrpt::obs::CObservation2DRangeScan::Create());
		w.close();
	}
	const auto laser = runOn(dir + "/laser.rawlog", dir + "/out_laser");
	EXPECT_EQ(laser.frames, 0u);
	EXPECT_EQ(laser.skipped, 3u);
	EXPECT_NE(laser.error.find("3 entries skipped"), std::string::npos) << laser.error;
	EXPECT_NE(laser.error.find("CObservation2DRangeScan is not an RGB-D observation"), std::string::npos) << laser.error;
}

TEST(InputChecks, FramesWhoseTimeDoesNotGoForwardAreSkippedAndCounted)
{
	const std::string dir = test::scratchDir("input_checks_time");
	// 1, 2, then 2 again, 1.5 (backwards), 0 (none), then 3 and 4.
	const std::vector<double> stamps = {1.0, 2.0, 2.0, 1.5, 0.0, 3.0, 4.0};
	{
		core::RawlogWriter w(dir + "/time.rawlog");
		for (const double t : stamps) w.write(core::makeRgbdObservation(texturedFrame(t)));
		w.close();
	}
	const auto r = runOn(dir + "/time.rawlog", dir + "/out");
	ASSERT_TRUE(r.error.empty()) << r.error;
	EXPECT_EQ(r.frames, 4u);
	EXPECT_EQ(r.skipped, 3u);
	EXPECT_NE(r.lastSkip.find("is missing"), std::string::npos) << r.lastSkip;
	const auto traj = core::readTumTrajectory(dir + "/out/trajectory.txt");
	ASSERT_EQ(traj.size(), 4u);
	const double expected[] = {1.0, 2.0, 3.0, 4.0};
	for (std::size_t i = 0; i < traj.size(); i++) EXPECT_NEAR(traj[i].t, expected[i], 1e-6);
}

TEST(InputChecks, ErrorsFromInsideMrptAreOneReadableLine)
{
	const std::string dir = test::scratchDir("input_checks_mrpt_errors");
	{
		core::RawlogWriter w(dir + "/one.rawlog");
		w.write(core::makeRgbdObservation(texturedFrame(1.0)));
		w.close();
	}
	const std::string tool = test::toolPath("keygrid-slam");
	std::string out;
	// A map plugin's option refused while MRPT's map factory builds it: MRPT wraps the reason
	// in its exception text with a backtrace; the one line printed is the reason itself.
	std::ofstream(dir + "/fine.ini") << "[MappingApplication]\nsubmappedOccupancyGrid3D_count = 1\n"
									 << "[MappingApplication_submappedOccupancyGrid3D_00_creationOpts]\nresolution = 0.001\n";
	EXPECT_EQ(test::runCommand(tool + " --config " + dir + "/fine.ini --input " + dir + "/one.rawlog --output " + dir + "/out", &out), 1);
	EXPECT_NE(out.find("keygrid-slam: error: [MappingApplication_submappedOccupancyGrid3D_00_creationOpts] resolution = 0.001 (must be in [0.005, 10])\n"),
			  std::string::npos)
		<< out;
	EXPECT_EQ(out.find("0x"), std::string::npos) << "no backtrace address: " << out;
	// A device is neither a rawlog nor a TUM folder.
	EXPECT_EQ(test::runCommand(tool + " --config " + dir + "/fine.ini --input /dev/zero --output " + dir + "/out", &out), 1);
	EXPECT_NE(out.find("input '/dev/zero' is neither a rawlog file nor a TUM folder"), std::string::npos) << out;
}
