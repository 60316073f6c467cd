#include <keygrid/core/AtomicOutput.h>
// RawlogWriter (RawlogWriter.h): the temp-file-then-rename contract under write failures.
#include <keygrid/core/Frame.h>
#include <keygrid/core/RawlogWriter.h>
#include <keygrid/core/RgbdObservation.h>
#include <mrpt/system/filesystem.h>
#include <opencv2/core.hpp>

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "TestData.h"

using namespace keygrid::core;

// A full disk: the temp file is a link to /dev/full, where every write fails with ENOSPC.
// The writer must report it (not crash while closing: zlib keeps the input it could not
// compress and gzclose() compresses it again, which read the caller's freed image buffers
// under AddressSanitizer), refuse later writes, and leave no file under the final name.
TEST(RawlogWriter, AFullDiskIsReportedAndNothingIsLeftBehind)
{
	if (!mrpt::system::fileExists("/dev/full")) GTEST_SKIP() << "/dev/full missing";
	const std::string dir = keygrid::test::scratchDir("rawlog_full_disk");
	const std::string path = dir + "/full.rawlog";
	const std::string tmp = keygrid::core::atomicTmpPath(path);
	std::remove(tmp.c_str());
	std::filesystem::create_symlink("/dev/full", tmp);
	Frame f;
	f.camera.width = 640;
	f.camera.height = 480;
	f.grey = cv::Mat(480, 640, CV_8UC1);
	f.colour = cv::Mat(480, 640, CV_8UC3);
	cv::randu(f.grey, 0, 256);  // incompressible, and each image written in one piece larger
	cv::randu(f.colour, 0, 256);  // than zlib's buffers (zlib then compresses it in place)
	f.depthRaw = cv::Mat(480, 640, CV_16UC1, cv::Scalar(5000));
	{
		RawlogWriter w(path);
		bool threw = false;
		try
		{
			for (int i = 0; i < 5; i++) w.write(makeRgbdObservation(f));  // each dropped at once
		}
		catch (const std::exception& e)
		{
			threw = true;
			EXPECT_NE(std::string(e.what()).find("cannot write '" + path + "': No space left on device"), std::string::npos) << e.what();
		}
		EXPECT_TRUE(threw);
		EXPECT_THROW(w.write(makeRgbdObservation(f)), std::runtime_error);  // no retry into zlib
		EXPECT_THROW(w.close(), std::runtime_error);
	}  // the destructor closes the stream (ASan: no use after free) and drops the temp file
	EXPECT_FALSE(mrpt::system::fileExists(path));
	EXPECT_FALSE(std::filesystem::is_symlink(tmp));
}

// An output path that is a folder is refused when the writer is made, before any frame is
// converted, and nothing is created beside it.
TEST(RawlogWriter, AFolderAsOutputIsRefusedBeforeAnyFrame)
{
	const std::string dir = keygrid::test::scratchDir("rawlog_folder_output");
	const std::string path = dir + "/existing";
	std::filesystem::create_directories(path);
	try
	{
		RawlogWriter w(path);
		FAIL() << "no exception";
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_NE(std::string(e.what()).find("'" + path + "' is a folder"), std::string::npos) << e.what();
	}
	EXPECT_FALSE(std::filesystem::exists(keygrid::core::atomicTmpPath(path)));
}
