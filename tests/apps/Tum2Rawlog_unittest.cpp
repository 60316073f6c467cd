#include <keygrid/core/AtomicOutput.h>
// keygrid-tum2rawlog run as a user would: output readable by rawlog-edit, clear errors.
#include <keygrid/core/RawlogFrameSource.h>
#include <mrpt/system/filesystem.h>

#include "SyntheticTum.h"
#include "TestData.h"

#include <fstream>

using keygrid::test::runCommand;
using keygrid::test::toolPath;

namespace
{
std::string tool() { return toolPath("keygrid-tum2rawlog"); }
}  // namespace

TEST(Tum2Rawlog, ConvertsAndRawlogEditReadsIt)
{
	const std::string dir = keygrid::test::scratchDir("t2r_ok");
	const auto s = keygrid::test::writeSyntheticTum(dir + "/seq", 6, 64, 48);
	std::ofstream(s.dir + "/camera.ini") << "[camera]\nwidth=64\nheight=48\nfx=60\nfy=60\ncx=31.5\ncy=23.5\n";
	std::string out;
	ASSERT_EQ(runCommand(tool() + " --quiet --input " + s.dir + " --output " + dir + "/o.rawlog", &out), 0) << out;
	EXPECT_NE(out.find("wrote 6 CObservation3DRangeScan"), std::string::npos) << out;
	EXPECT_FALSE(mrpt::system::fileExists(keygrid::core::atomicTmpPath(dir + "/o.rawlog")));
	if (!mrpt::system::fileExists("/usr/bin/rawlog-edit")) GTEST_SKIP() << "rawlog-edit missing (mrpt-apps)";
	ASSERT_EQ(runCommand("rawlog-edit --info -i " + dir + "/o.rawlog", &out), 0) << out;
	EXPECT_NE(out.find("Overall number of objects         : 6"), std::string::npos) << out;
	ASSERT_EQ(runCommand("rawlog-edit --list-timestamps -i " + dir + "/o.rawlog --text-file-output " + dir + "/ts.txt", &out), 0) << out;
	std::ifstream ts(dir + "/ts.txt");
	std::string line;
	int obs3d = 0;
	while (std::getline(ts, line)) obs3d += line.find("CObservation3DRangeScan") != std::string::npos;
	EXPECT_EQ(obs3d, 6);
}

TEST(Tum2Rawlog, SharedFr1DeskGivesNineObservations)
{
	KEYGRID_SKIP_WITHOUT_SHARED_DATA("tum_fr1_desk_9frames");
	const std::string dir = keygrid::test::scratchDir("t2r_fr1");
	std::string out;
	ASSERT_EQ(runCommand(tool() + " --input " + keygrid::test::sharedDataDir() + "/tum_fr1_desk_9frames --output " + dir + "/d.rawlog", &out), 0) << out;
	keygrid::core::RawlogFrameSource src(dir + "/d.rawlog");
	keygrid::core::Frame f;
	int n = 0;
	while (src.next(f)) ++n;
	EXPECT_EQ(n, 9);
	EXPECT_EQ(f.camera.name, "fr1");
	ASSERT_EQ(runCommand("rawlog-edit --info -i " + dir + "/d.rawlog", &out), 0) << out;
	EXPECT_NE(out.find("Overall number of objects         : 9"), std::string::npos) << out;
}

TEST(Tum2Rawlog, BadInputsGiveOneLineReasons)
{
	const std::string dir = keygrid::test::scratchDir("t2r_bad");
	auto expectFail = [&](const std::string& args, int code, const std::string& needle) {
		std::string out;
		EXPECT_EQ(runCommand(tool() + " " + args, &out), code) << args << "\n" << out;
		EXPECT_NE(out.find(needle), std::string::npos) << args << "\n" << out;
		EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << "not one line:\n" << out;
	};
	expectFail("", 2, "missing --input");
	expectFail("--input x --output y --frobnicate", 2, "unknown option --frobnicate");
	expectFail("--input /nonexistent/tum --output " + dir + "/a.rawlog", 1, "does not exist");
	expectFail("--input " + dir + " --output " + dir + "/a.rawlog", 1, "associations.txt");
	// empty lists
	const std::string empty = dir + "/empty";
	mrpt::system::createDirectory(empty);
	std::ofstream(empty + "/rgb.txt") << "# header only\n";
	std::ofstream(empty + "/depth.txt") << "# header only\n";
	expectFail("--input " + empty + " --output " + dir + "/a.rawlog", 1, "no rgb/depth pair");
	// unreadable PNG
	auto s = keygrid::test::writeSyntheticTum(dir + "/corrupt", 2, 64, 48);
	std::ofstream(s.dir + "/camera.ini") << "[camera]\nwidth=64\nheight=48\n";
	std::ofstream(s.dir + "/rgb/" + [&] { char b[64]; std::snprintf(b, 64, "%.6f.png", s.tRgb[1]); return std::string(b); }()) << "garbage";
	expectFail("--quiet --input " + s.dir + " --output " + dir + "/a.rawlog", 1, "cannot decode image");
	EXPECT_FALSE(mrpt::system::fileExists(dir + "/a.rawlog")) << "a failed run must not leave a rawlog";
	// mismatched sizes: the camera says 640x480
	auto m = keygrid::test::writeSyntheticTum(dir + "/small", 1, 64, 48);
	expectFail("--quiet --camera fr1 --input " + m.dir + " --output " + dir + "/a.rawlog", 1, "64x48");
	expectFail("--quiet --camera fr7 --input " + m.dir + " --output " + dir + "/a.rawlog", 1, "unknown camera preset");
	std::string out;
	EXPECT_EQ(runCommand(tool() + " --help", &out), 0);
	EXPECT_NE(out.find("--external-images"), std::string::npos);
}
