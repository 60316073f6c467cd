// keygrid-slam on bad inputs, run as a user would: each class of bad input gives a clear error
// naming it, or a counted and logged skip, and never a death by signal (also under ASan+UBSan).
#include <keygrid/core/RgbdObservation.h>
#include <mrpt/system/filesystem.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include "SlamRunHelpers.h"
#include "SyntheticTum.h"
#include "TestData.h"

using namespace keygrid;
using test::ToolRun;

namespace
{
std::string slamArgs(const std::string& cfg, const std::string& input, const std::string& out)
{
	return "--quiet --config " + cfg + " --input " + input + " --output " + out;
}

// Every run: a normal exit, never a signal (a crash, an abort, a sanitizer report).
#define EXPECT_EXITED(run)                                                                     \
	EXPECT_FALSE((run).signaled()) << "killed by signal " << (run).termSignal() << "\n" << (run).output; \
	EXPECT_GE((run).exitCode(), 0) << (run).output

std::vector<mrpt::obs::CObservation3DRangeScan::Ptr> goodObservations(std::size_t n)
{
	std::vector<mrpt::obs::CObservation3DRangeScan::Ptr> v;
	for (std::size_t i = 0; i < n; i++) v.push_back(test::texturedObservation(i));
	return v;
}

std::string readBytes(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	return std::string(std::istreambuf_iterator<char>(f), {});
}

/** A 40x30 crop of texturedFrame(i): rawlogs of these are mostly structure, not pixels. */
mrpt::obs::CObservation3DRangeScan::Ptr tinyObservation(std::size_t i)
{
	core::Frame f = test::texturedFrame(i);
	const cv::Rect roi(0, 0, 40, 30);
	f.grey = f.grey(roi).clone();
	f.colour = f.colour(roi).clone();
	f.depth = f.depth(roi).clone();
	f.camera.width = 40;
	f.camera.height = 30;
	f.camera.cx = 19.5;
	f.camera.cy = 14.5;
	return core::makeRgbdObservation(f);
}

void writeBytes(const std::string& path, const std::string& bytes)
{
	std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}
}  // namespace

TEST(Robustness, NonexistentPathsAreNamed)
{
	const std::string dir = test::scratchDir("robust_paths");
	const std::string cfg = test::writeFastConfig(dir + "/fast.ini");
	const std::string rawlog = dir + "/ok.rawlog";
	test::writeRawlog(rawlog, goodObservations(2));

	const ToolRun noInput = test::runTool("keygrid-slam", slamArgs(cfg, dir + "/missing.rawlog", dir + "/o1"));
	EXPECT_EXITED(noInput);
	EXPECT_EQ(noInput.exitCode(), 1);
	EXPECT_NE(noInput.output.find("keygrid-slam: error: input '" + dir + "/missing.rawlog' does not exist"), std::string::npos) << noInput.output;

	const ToolRun noConfig = test::runTool("keygrid-slam", slamArgs(dir + "/missing.ini", rawlog, dir + "/o2"));
	EXPECT_EXITED(noConfig);
	EXPECT_EQ(noConfig.exitCode(), 1);
	EXPECT_NE(noConfig.output.find("'" + dir + "/missing.ini' does not exist"), std::string::npos) << noConfig.output;

	const ToolRun noGt = test::runTool("keygrid-slam", slamArgs(cfg, rawlog, dir + "/o3") + " --gt " + dir + "/missing_gt.txt");
	EXPECT_EXITED(noGt);
	EXPECT_EQ(noGt.exitCode(), 1);
	EXPECT_NE(noGt.output.find(dir + "/missing_gt.txt"), std::string::npos) << noGt.output;

	// The output folder cannot be created below a regular file.
	const ToolRun badOut = test::runTool("keygrid-slam", slamArgs(cfg, rawlog, rawlog + "/out"));
	EXPECT_EXITED(badOut);
	EXPECT_EQ(badOut.exitCode(), 1);
	EXPECT_NE(badOut.output.find("cannot create"), std::string::npos) << badOut.output;
	EXPECT_NE(badOut.output.find(rawlog + "/out"), std::string::npos) << badOut.output;

	const ToolRun noTum = test::runTool("keygrid-slam", slamArgs(cfg, dir + "/missing_tum/", dir + "/o4"));
	EXPECT_EXITED(noTum);
	EXPECT_EQ(noTum.exitCode(), 1);
	EXPECT_NE(noTum.output.find(dir + "/missing_tum"), std::string::npos) << noTum.output;
}

TEST(Robustness, TruncatedRawlogKeepsTheFramesBeforeTheCut)
{
	const std::string dir = test::scratchDir("robust_truncated");
	const std::string cfg = test::writeFastConfig(dir + "/fast.ini");
	for (int level : {0, 1})
	{
		SCOPED_TRACE("gzip level " + std::to_string(level));
		const std::string rawlog = dir + "/cut" + std::to_string(level) + ".rawlog";
		test::writeRawlog(rawlog, goodObservations(6), level);
		const std::string bytes = readBytes(rawlog);
		// Cut in the middle of the 5th observation (uncompressed observations are equal-sized).
		writeBytes(rawlog, bytes.substr(0, bytes.size() * 9 / 12));
		const std::string out = dir + "/out" + std::to_string(level);
		const ToolRun r = test::runTool("keygrid-slam", slamArgs(cfg, rawlog, out));
		EXPECT_EXITED(r);
		EXPECT_EQ(r.exitCode(), 1) << r.output;
		EXPECT_NE(r.output.find("rawlog '" + rawlog + "' is corrupt or truncated"), std::string::npos) << r.output;
		ASSERT_TRUE(mrpt::system::fileExists(out + "/report.json")) << r.output;
		const std::string report = test::readTextFile(out + "/report.json");
		const double frames = test::jsonNumber(report, "frames");
		EXPECT_GE(frames, 3) << report;
		EXPECT_LT(frames, 6) << report;
		EXPECT_EQ(test::countPoseLines(out + "/trajectory.txt"), static_cast<std::size_t>(frames));
		EXPECT_NE(report.find("\"error\": \"rawlog '"), std::string::npos) << report;
	}
}

// A damaged range image size (the high byte of an entry's cols) would make MRPT write through
// a null allocation: it is named before MRPT reads it, and the earlier frames' outputs stay.
TEST(Robustness, DamagedRangeImageSizeIsNamedAndTheEarlierFramesKept)
{
	const std::string dir = test::scratchDir("robust_range_size");
	const std::string cfg = test::writeFastConfig(dir + "/fast.ini");
	const std::string rawlog = dir + "/damaged.rawlog";
	test::writeRawlog(rawlog, {tinyObservation(0), tinyObservation(1), tinyObservation(2)});
	std::string bytes = readBytes(rawlog);
	// The third entry's range image size: the first (rows, cols) = (30, 40) after its class name.
	std::size_t at = 0;
	for (int k = 0; k < 3; k++) at = bytes.find("mrpt::obs::CObservation3DRangeScan", at + 1);
	ASSERT_NE(at, std::string::npos);
	at = bytes.find(std::string("\x1e\0\0\0\x28\0\0\0", 8), at);
	ASSERT_NE(at, std::string::npos);
	bytes[at + 7] = '\x7f';
	writeBytes(rawlog, bytes);

	const ToolRun r = test::runTool("keygrid-slam", slamArgs(cfg, rawlog, dir + "/out"));
	EXPECT_EXITED(r);
	EXPECT_EQ(r.exitCode(), 1) << r.output;
	EXPECT_NE(r.output.find("keygrid-slam: error: rawlog '" + rawlog + "' is corrupt or truncated at entry 2 (byte "), std::string::npos) << r.output;
	EXPECT_NE(r.output.find("range image of 2130706472 x 30 pixels"), std::string::npos) << r.output;
	EXPECT_EQ(test::countPoseLines(dir + "/out/trajectory.txt"), 2u) << r.output;

	const ToolRun v = test::runTool("keygrid-vocab", "train --rawlog " + rawlog + " --output " + dir + "/v.voc");
	EXPECT_EXITED(v);
	EXPECT_EQ(v.exitCode(), 1) << v.output;
	EXPECT_NE(v.output.find("is corrupt or truncated at entry 2"), std::string::npos) << v.output;
	EXPECT_FALSE(mrpt::system::fileExists(dir + "/v.voc"));
}

// A full disk, made by a file size limit (RLIMIT_FSIZE, with SIGXFSZ ignored: writes past the
// limit fail with EFBIG): the run ends with an error naming the file, and every output file it
// leaves is whole: byte-identical to an unlimited run's (report.json, with its timings, a
// complete JSON object). No temporary file stays behind.
TEST(Robustness, AFullDiskNamesTheFileAndLeavesNoPartialOutput)
{
	const std::string dir = test::scratchDir("robust_full_disk");
	const std::string cfg = test::writeFastConfig(dir + "/fast_maps.ini", true);
	const std::string rawlog = dir + "/seq.rawlog";
	test::writeRawlog(rawlog, goodObservations(4));
	const ToolRun ref = test::runTool("keygrid-slam", slamArgs(cfg, rawlog, dir + "/ref"));
	ASSERT_EQ(ref.exitCode(), 0) << ref.output;
	std::map<std::string, std::uintmax_t> refSizes;
	for (const auto& e : std::filesystem::directory_iterator(dir + "/ref")) refSizes[e.path().filename().string()] = e.file_size();
	ASSERT_GE(refSizes.size(), 10u);
	std::uintmax_t largest = 0;
	for (const auto& [name, size] : refSizes) largest = std::max(largest, size);

	// Limits in 512-byte blocks: below the smallest files, and below the largest only.
	for (const std::uintmax_t blocks : {std::uintmax_t{1}, std::uintmax_t{4}, (largest - 1) / 512})
	{
		SCOPED_TRACE("limit " + std::to_string(blocks * 512) + " bytes");
		const std::string out = dir + "/out" + std::to_string(blocks);
		const ToolRun r = test::runTool("keygrid-slam", slamArgs(cfg, rawlog, out), "trap '' XFSZ; ulimit -f " + std::to_string(blocks) + ";");
		EXPECT_EXITED(r);
		EXPECT_EQ(r.exitCode(), 1) << r.output;
		EXPECT_NE(r.output.find("keygrid-slam: error: "), std::string::npos) << r.output;
		EXPECT_NE(r.output.find("cannot write '" + out + "/"), std::string::npos) << r.output;
		EXPECT_NE(r.output.find("File too large"), std::string::npos) << r.output;
		std::size_t present = 0;
		for (const auto& e : std::filesystem::recursive_directory_iterator(out))
		{
			const std::string name = e.path().filename().string();
			EXPECT_EQ(name.find(".tmp"), std::string::npos) << "left behind: " << e.path();
			if (!e.is_regular_file()) continue;
			present++;
			EXPECT_LE(e.file_size(), blocks * 512) << name;
			if (name == "report.json")
			{
				const std::string report = test::readTextFile(e.path().string());
				EXPECT_EQ(report.substr(report.size() - 2), "}\n") << report;
			}
			else
			{
				EXPECT_EQ(readBytes(e.path().string()), readBytes(dir + "/ref/" + name)) << name << " differs from the unlimited run's";
			}
		}
		EXPECT_LT(present, refSizes.size());
	}
}

TEST(Robustness, ObservationsWithoutDepthImageOrValidCalibrationAreSkippedAndCounted)
{
	const std::string dir = test::scratchDir("robust_skips");
	const std::string cfg = test::writeFastConfig(dir + "/fast.ini");
	auto obs = goodObservations(9);
	obs[1]->hasRangeImage = false;
	obs[1]->rangeImage.resize(0, 0);
	obs[3]->hasIntensityImage = false;
	obs[3]->intensityImage = mrpt::img::CImage();
	obs[4]->rangeImage.resize(60, 80);  // depth 80x60, image 160x120
	obs[5]->cameraParamsIntensity.ncols = 320;  // calibration of another resolution
	obs[5]->cameraParams = obs[5]->cameraParamsIntensity;
	obs[6]->cameraParamsIntensity.fx(std::nan(""));  // NaN intrinsics
	obs[6]->cameraParams = obs[6]->cameraParamsIntensity;
	obs[7]->rangeUnits = std::numeric_limits<float>::infinity();
	const std::string rawlog = dir + "/skips.rawlog";
	test::writeRawlog(rawlog, obs);

	const std::string out = dir + "/out";
	const ToolRun r = test::runTool("keygrid-slam", slamArgs(cfg, rawlog, out));
	EXPECT_EXITED(r);
	EXPECT_EQ(r.exitCode(), 0) << r.output;
	// Logged: one warning line with the count and the last reason.
	EXPECT_NE(r.output.find("keygrid-slam: warning: skipped 6 input entries (last: rawlog entry 7: invalid rangeUnits inf)"), std::string::npos) << r.output;
	const std::string report = test::readTextFile(out + "/report.json");
	EXPECT_EQ(test::jsonNumber(report, "frames"), 3) << report;
	EXPECT_EQ(test::jsonNumber(report, "skipped_input_entries"), 6) << report;
	EXPECT_EQ(test::countPoseLines(out + "/trajectory.txt"), 3u);

	// The reasons, one by one, from the reading code itself.
	const char* expected[] = {nullptr, "no range image", nullptr, "no intensity image", "differ in size",
							  "intensity camera parameters are for 320x120 but the image is 160x120",
							  "invalid intensity camera parameters", nullptr, nullptr};
	for (std::size_t i = 0; i < 7; i++)
	{
		core::Frame f;
		std::string why;
		const bool ok = core::frameFromObservation(*obs[i], f, &why);
		EXPECT_EQ(ok, expected[i] == nullptr) << i << ": " << why;
		if (expected[i])
		{
			EXPECT_NE(why.find(expected[i]), std::string::npos) << i << ": " << why;
		}
	}
}

TEST(Robustness, AllZeroDepthIsProcessedWithMapsAndReported)
{
	const std::string dir = test::scratchDir("robust_zero_depth");
	const std::string cfg = test::writeFastConfig(dir + "/maps.ini", true);
	std::vector<mrpt::obs::CObservation3DRangeScan::Ptr> obs;
	for (std::size_t i = 0; i < 5; i++) obs.push_back(test::texturedObservation(i, 0.0f));
	const std::string rawlog = dir + "/zero.rawlog";
	test::writeRawlog(rawlog, obs);
	const std::string out = dir + "/out";
	const ToolRun r = test::runTool("keygrid-slam", slamArgs(cfg, rawlog, out));
	EXPECT_EXITED(r);
	EXPECT_LE(r.exitCode(), 1) << r.output;
	ASSERT_TRUE(mrpt::system::fileExists(out + "/report.json")) << r.output;
	const std::string report = test::readTextFile(out + "/report.json");
	EXPECT_EQ(test::jsonNumber(report, "frames"), 5) << report;
	// No depth: nothing can be initialised, every frame is reported lost.
	EXPECT_EQ(test::jsonNumber(report, "tracked"), 0) << report;
	EXPECT_EQ(test::jsonNumber(report, "lost"), 5) << report;
	EXPECT_EQ(test::countPoseLines(out + "/trajectory.txt"), 5u);
}

TEST(Robustness, NonFinitePosesInGroundTruthAreRejectedNamingFileAndLine)
{
	const std::string dir = test::scratchDir("robust_nan_gt");
	const std::string cfg = test::writeFastConfig(dir + "/fast.ini");
	const std::string rawlog = dir + "/ok.rawlog";
	test::writeRawlog(rawlog, goodObservations(3));
	const std::string good = "1000.0 0 0 0 0 0 0 1\n";
	for (const std::string bad : {"nan", "inf", "-inf", "1e999"})
	{
		SCOPED_TRACE(bad);
		const std::string gt = dir + "/gt_" + bad + ".txt";
		std::ofstream(gt) << "# timestamp tx ty tz qx qy qz qw\n" << good << "1000.1 0 " << bad << " 0 0 0 0 1\n";
		const ToolRun r = test::runTool("keygrid-slam", slamArgs(cfg, rawlog, dir + "/o_" + bad) + " --gt " + gt);
		EXPECT_EXITED(r);
		EXPECT_EQ(r.exitCode(), 1) << r.output;
		EXPECT_NE(r.output.find(gt + ":3"), std::string::npos) << r.output;
		EXPECT_NE(r.output.find("is not a finite number"), std::string::npos) << r.output;
		// keygrid-eval reads trajectories with the same reader.
		const ToolRun e = test::runTool("keygrid-eval", "--gt " + gt + " --est " + gt);
		EXPECT_EXITED(e);
		EXPECT_EQ(e.exitCode(), 1) << e.output;
		EXPECT_NE(e.output.find(gt + ":3"), std::string::npos) << e.output;
	}
}

TEST(Robustness, WrongImageSizesInTumFoldersAreNamed)
{
	const std::string dir = test::scratchDir("robust_tum_sizes");
	const std::string cfg = test::writeFastConfig(dir + "/fast.ini");
	// Images 64x48 but the folder's camera says 640x480.
	const auto s = test::writeSyntheticTum(dir + "/cam_mismatch", 3, 64, 48);
	std::ofstream(s.dir + "/camera.ini") << "[camera]\nwidth=640\nheight=480\nfx=500\nfy=500\ncx=319.5\ncy=239.5\n";
	const ToolRun r = test::runTool("keygrid-slam", slamArgs(cfg, s.dir, dir + "/o1"));
	EXPECT_EXITED(r);
	EXPECT_EQ(r.exitCode(), 1) << r.output;
	EXPECT_NE(r.output.find("is 64x48 but camera"), std::string::npos) << r.output;
	EXPECT_NE(r.output.find(s.dir + "/rgb/"), std::string::npos) << r.output;

	// Depth 32x24 beside colour 64x48.
	const auto t = test::writeSyntheticTum(dir + "/depth_size", 3, 64, 48);
	std::ofstream(t.dir + "/camera.ini") << "[camera]\nwidth=64\nheight=48\nfx=60\nfy=60\ncx=31.5\ncy=23.5\n";
	char depthName[64];
	std::snprintf(depthName, sizeof(depthName), "/depth/%.6f.png", t.tDepth[1]);
	ASSERT_TRUE(cv::imwrite(t.dir + depthName, cv::Mat(24, 32, CV_16UC1, cv::Scalar(5000))));
	const std::string out = dir + "/o2";
	const ToolRun d = test::runTool("keygrid-slam", slamArgs(cfg, t.dir, out));
	EXPECT_EXITED(d);
	EXPECT_EQ(d.exitCode(), 1) << d.output;
	EXPECT_NE(d.output.find("image sizes differ"), std::string::npos) << d.output;
	EXPECT_NE(d.output.find(t.dir + depthName + "' is 32x24"), std::string::npos) << d.output;
	// The frame before the bad one was processed and its outputs written.
	EXPECT_EQ(test::jsonNumber(test::readTextFile(out + "/report.json"), "frames"), 1);
}

TEST(Robustness, TumFolderWithBrokenLinesSkipsThemAndSaysWhere)
{
	const std::string dir = test::scratchDir("robust_tum_lines");
	const std::string cfg = test::writeFastConfig(dir + "/fast.ini");
	const auto s = test::writeSyntheticTum(dir + "/seq", 4, 64, 48);
	std::ofstream(s.dir + "/camera.ini") << "[camera]\nwidth=64\nheight=48\nfx=60\nfy=60\ncx=31.5\ncy=23.5\n";
	{
		std::ofstream a(s.dir + "/associations.txt", std::ios::app);
		a << "this line is garbage\n1305031460.0 rgb/only_two_fields.png\nnan rgb/x.png nan depth/x.png\n";
	}
	const std::string out = dir + "/out";
	const ToolRun r = test::runTool("keygrid-slam", slamArgs(cfg, s.dir, out));
	EXPECT_EXITED(r);
	EXPECT_EQ(r.exitCode(), 0) << r.output;
	EXPECT_NE(r.output.find("warning: skipped 3 input entries (last: " + s.dir + "/associations.txt:7"), std::string::npos) << r.output;
	const std::string report = test::readTextFile(out + "/report.json");
	EXPECT_EQ(test::jsonNumber(report, "frames"), 4) << report;
	EXPECT_EQ(test::jsonNumber(report, "skipped_input_entries"), 3) << report;

	// A line naming an image that is not there: a clear error after the frames before it.
	{
		std::ofstream a(s.dir + "/associations.txt", std::ios::app);
		a << "1305031470.0 rgb/gone.png 1305031470.0 depth/gone.png\n";
	}
	const ToolRun m = test::runTool("keygrid-slam", slamArgs(cfg, s.dir, dir + "/out2"));
	EXPECT_EXITED(m);
	EXPECT_EQ(m.exitCode(), 1) << m.output;
	EXPECT_NE(m.output.find("missing image '" + s.dir + "/rgb/gone.png'"), std::string::npos) << m.output;
	EXPECT_EQ(test::jsonNumber(test::readTextFile(dir + "/out2/report.json"), "frames"), 4);

	// Nothing usable at all.
	const std::string empty = dir + "/empty";
	std::filesystem::create_directories(empty);
	std::ofstream(empty + "/associations.txt") << "# only a comment\nbroken\n";
	const ToolRun e = test::runTool("keygrid-slam", slamArgs(cfg, empty, dir + "/out3"));
	EXPECT_EXITED(e);
	EXPECT_EQ(e.exitCode(), 1) << e.output;
	EXPECT_NE(e.output.find("gives no rgb/depth pair"), std::string::npos) << e.output;
}

// Fuzz-style: a fixed-seed series of byte-level corruptions of a small valid rawlog and of a
// valid INI. Whatever the damage, keygrid-slam must end by exit (error or success), never by
// a signal.
TEST(Robustness, FuzzedRawlogsAndConfigsNeverKillTheProcess)
{
	const std::string dir = test::scratchDir("robust_fuzz");
	const std::string cfg = test::writeFastConfig(dir + "/fast.ini");
	const std::string base = dir + "/base.rawlog";
	const std::vector<mrpt::obs::CObservation3DRangeScan::Ptr> tiny{tinyObservation(0), tinyObservation(1), tinyObservation(2)};
	test::writeRawlog(base, tiny);
	const std::string rawBytes = readBytes(base);
	test::writeRawlog(dir + "/basegz.rawlog", tiny, 1);
	const std::string gzBytes = readBytes(dir + "/basegz.rawlog");
	const std::string iniBytes = readBytes(test::writeFastConfig(dir + "/fast_maps.ini", true));
	ASSERT_GT(rawBytes.size(), 1000u);
	// The uncorrupted inputs run cleanly.
	ASSERT_EQ(test::runTool("keygrid-slam", slamArgs(dir + "/fast_maps.ini", base, dir + "/base_out")).exitCode(), 0);

	std::mt19937 rng(20261121);
	auto mutate = [&](std::string b, int kind) {
		std::uniform_int_distribution<std::size_t> pos(0, b.size() - 1);
		switch (kind)
		{
			case 0:  // flip a few random bits
				for (int k = 0; k < 4; k++) b[pos(rng)] ^= static_cast<char>(1u << (rng() % 8));
				break;
			case 1:  // truncate anywhere
				b.resize(pos(rng));
				break;
			case 2:  // overwrite a 4-byte window (lengths, counts, class names) with 0xFF
				for (std::size_t p = pos(rng), k = 0; k < 4 && p + k < b.size(); k++) b[p + k] = '\xff';
				break;
			default:  // random bytes over a short run
				for (std::size_t p = pos(rng), k = 0; k < 16 && p + k < b.size(); k++) b[p + k] = static_cast<char>(rng());
		}
		return b;
	};
	// Sanitizer builds: a corrupted size field asks for terabytes; let ASan's allocator fail
	// as the real one does (std::bad_alloc) instead of reporting and aborting.
	const char* asan = std::getenv("ASAN_OPTIONS");
	const std::string env = std::string("ASAN_OPTIONS='") + (asan ? asan : "") + ":allocator_may_return_null=1'";
	int exits = 0, failures = 0;
	// 20 corrupted uncompressed rawlogs, 6 corrupted gzip rawlogs, 10 corrupted INI files.
	const int cases = 36;
	for (int c = 0; c < cases; c++)
	{
		const bool ini = c >= 26;
		const bool gz = c >= 20 && !ini;
		const std::string name = dir + "/case" + std::to_string(c);
		std::string cfgPath = cfg, input = base;
		if (ini)
		{
			cfgPath = name + ".ini";
			writeBytes(cfgPath, mutate(iniBytes, c % 4));
		}
		else
		{
			input = name + ".rawlog";
			writeBytes(input, mutate(gz ? gzBytes : rawBytes, c % 4));
		}
		const ToolRun r = test::runTool("keygrid-slam", slamArgs(cfgPath, input, name + "_out"), env);
		EXPECT_FALSE(r.signaled()) << "case " << c << ": killed by signal " << r.termSignal() << "\n" << r.output;
		EXPECT_TRUE(r.exitCode() == 0 || r.exitCode() == 1) << "case " << c << ": exit " << r.exitCode() << "\n" << r.output;
		exits += r.exitCode() >= 0;
		failures += r.exitCode() == 1;
		// A failure says why in one "keygrid-slam: error:" line.
		if (r.exitCode() == 1)
		{
			EXPECT_NE(r.output.find("keygrid-slam: error: "), std::string::npos) << "case " << c << "\n" << r.output;
		}
	}
	EXPECT_EQ(exits, cases);
	// Most corruptions are detected (some land in pixels or comments and are harmless).
	EXPECT_GT(failures, 10);
}
