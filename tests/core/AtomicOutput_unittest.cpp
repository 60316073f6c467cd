/** \file AtomicOutput_unittest.cpp
 * The one output writer: files appear whole or not at all. A full disk (/dev/full behind the
 * temporary name) is reported naming the file, also when it only shows at close; a file that
 * had the name keeps its old content; gzip output is byte-identical to MRPT's own writer.
 */
#include <keygrid/core/AtomicOutput.h>
#include <gtest/gtest.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/system/filesystem.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "TestChecks.h"
#include "TestData.h"

using namespace keygrid::core;
using keygrid::test::errorOf;

namespace
{
std::string bytesOf(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	std::ostringstream s;
	s << f.rdbuf();
	return s.str();
}

/** Points the temporary name of `path` at /dev/full: every write there fails with ENOSPC. */
void fullDiskFor(const std::string& path)
{
	std::filesystem::remove(atomicTmpPath(path));
	std::filesystem::create_symlink("/dev/full", atomicTmpPath(path));
}

}  // namespace

TEST(AtomicOutput, TemporaryNamesKeepTheExtensionLast)
{
	EXPECT_EQ(atomicTmpPath("/a/b/map_2d.png"), "/a/b/map_2d.tmp.png");
	EXPECT_EQ(atomicTmpPath("out/report"), "out/report.tmp");
	EXPECT_EQ(atomicTmpPath("x.tar.gz"), "x.tar.tmp.gz");
}

TEST(AtomicOutput, AFullDiskIsNamedAndTheOldFileIsKept)
{
	if (!mrpt::system::fileExists("/dev/full")) GTEST_SKIP() << "/dev/full missing";
	const std::string dir = keygrid::test::scratchDir("atomic_output_full");
	const std::string txt = dir + "/report.json", gz = dir + "/map.bin", png = dir + "/image.png";
	for (const auto& p : {txt, gz, png}) std::ofstream(p) << "old";

	// 20 bytes: they sit in the stream's buffer until the flush at close.
	fullDiskFor(txt);
	EXPECT_EQ(errorOf<std::runtime_error>([&] { writeFileAtomically(txt, std::string(20, 'x')); }), "cannot write '" + txt + "': No space left on device");
	// Small gzip data: zlib keeps it until gzclose().
	fullDiskFor(gz);
	EXPECT_EQ(
		errorOf<std::runtime_error>([&] { writeGzAtomically(gz, [](mrpt::io::CStream& s) { s.Write("abc", 3); }); }),
		"cannot write '" + gz + "': No space left on device");
	// Large gzip data: the failure shows in a write; later writes and the commit fail too.
	fullDiskFor(gz);
	{
		AtomicGzFile f(gz);
		std::vector<char> noise(4 << 20);
		cv::randu(cv::Mat(1, static_cast<int>(noise.size()), CV_8UC1, noise.data()), 0, 256);
		EXPECT_NE(errorOf<std::runtime_error>([&] { f.Write(noise.data(), noise.size()); }).find("No space left on device"), std::string::npos);
		EXPECT_NE(errorOf<std::runtime_error>([&] { f.Write("a", 1); }).find("an earlier write failed"), std::string::npos);
		EXPECT_NE(errorOf<std::runtime_error>([&] { f.commit(); }).find("an earlier write failed"), std::string::npos);
	}
	// A writer that takes a file name.
	fullDiskFor(png);
	const cv::Mat img(64, 64, CV_8UC1, cv::Scalar(7));
	EXPECT_NE(errorOf<std::runtime_error>([&] { writeFileThrough(png, [&](const std::string& tmp) { return cv::imwrite(tmp, img); }); }), "");

	for (const auto& p : {txt, gz, png})
	{
		EXPECT_EQ(bytesOf(p), "old") << p;
		EXPECT_FALSE(std::filesystem::is_symlink(atomicTmpPath(p))) << "temporary file left: " << atomicTmpPath(p);
	}
}

TEST(AtomicOutput, WritersProduceTheFileAndNothingElse)
{
	const std::string dir = keygrid::test::scratchDir("atomic_output_ok");
	writeFileAtomically(dir + "/a.txt", "hello\n");
	EXPECT_EQ(bytesOf(dir + "/a.txt"), "hello\n");
	writeFileAtomically(dir + "/b.txt", [](std::ostream& f) { f << "x = " << 42 << '\n'; });
	EXPECT_EQ(bytesOf(dir + "/b.txt"), "x = 42\n");

	// The format follows the final name's extension: a PNG that OpenCV reads back.
	const cv::Mat img(30, 40, CV_8UC1, cv::Scalar(99));
	writeFileThrough(dir + "/c.png", [&](const std::string& tmp) { return cv::imwrite(tmp, img); });
	const cv::Mat back = cv::imread(dir + "/c.png", cv::IMREAD_UNCHANGED);
	ASSERT_EQ(back.size(), img.size());
	EXPECT_EQ(cv::countNonZero(back != img), 0);
	// A writer that fails, or writes nothing, leaves nothing.
	EXPECT_NE(errorOf<std::runtime_error>([&] { writeFileThrough(dir + "/d.png", [](const std::string&) { return false; }); }).find("'" + dir + "/d.png'"), std::string::npos);
	EXPECT_NE(errorOf<std::runtime_error>([&] { writeFileThrough(dir + "/e.png", [](const std::string&) { return true; }); }).find("produced no file"), std::string::npos);
	// A folder under the name is refused.
	std::filesystem::create_directories(dir + "/f.txt");
	EXPECT_NE(errorOf<std::runtime_error>([&] { writeFileAtomically(dir + "/f.txt", "x"); }).find("it is a folder"), std::string::npos);

	std::vector<std::string> names;
	for (const auto& e : std::filesystem::directory_iterator(dir)) names.push_back(e.path().filename().string());
	std::sort(names.begin(), names.end());
	EXPECT_EQ(names, (std::vector<std::string>{"a.txt", "b.txt", "c.png", "f.txt"}));
}

TEST(AtomicOutput, GzipBytesEqualMrptsOwnWriter)
{
	const std::string dir = keygrid::test::scratchDir("atomic_output_gz");
	std::vector<char> data(3 << 20);
	for (std::size_t i = 0; i < data.size(); i++) data[i] = static_cast<char>((i * 2654435761u) >> 27);
	for (const int level : {1, 6})
	{
		{
			mrpt::io::CFileGZOutputStream m;
			ASSERT_TRUE(m.open(dir + "/mrpt.gz", level));
			m.Write(data.data(), 1000);
			m.Write(data.data() + 1000, data.size() - 1000);
		}
		writeGzAtomically(
			dir + "/ours.gz",
			[&](mrpt::io::CStream& s) {
				for (std::size_t at = 0; at < data.size(); at += 70000) s.Write(data.data() + at, std::min<std::size_t>(70000, data.size() - at));
			},
			level);
		EXPECT_EQ(bytesOf(dir + "/ours.gz"), bytesOf(dir + "/mrpt.gz")) << "level " << level;
	}
}
