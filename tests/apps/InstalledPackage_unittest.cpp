// An installed keygrid works: from another CMake project through find_package(keygrid), and its
// tools from any prefix.
#include "TestData.h"

#include <mrpt/system/filesystem.h>
#include <nlohmann/json.hpp>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <iostream>

using keygrid::test::runCommand;

TEST(InstalledPackage, FindPackageFromAConsumerProject)
{
	const std::string dir = keygrid::test::scratchDir("install_consumer");
	const std::string prefix = dir + "/prefix";
	std::string out;
	ASSERT_EQ(runCommand("cmake --install " + std::string(KEYGRID_TEST_BINARY_DIR) + " --prefix " + prefix, &out), 0) << out;
	ASSERT_TRUE(mrpt::system::fileExists(prefix + "/lib/cmake/keygrid/keygridConfig.cmake") ||
				mrpt::system::fileExists(prefix + "/lib/x86_64-linux-gnu/cmake/keygrid/keygridConfig.cmake"))
		<< out;
	const std::string src = keygrid::test::sourceDir() + "/tests/packaging/consumer";
	ASSERT_EQ(runCommand("cmake -S " + src + " -B " + dir + "/build -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=" + prefix, &out), 0) << out;
	ASSERT_EQ(runCommand("cmake --build " + dir + "/build -j2", &out), 0) << out;
	ASSERT_EQ(runCommand(dir + "/build/keygrid_consumer", &out), 0) << out;
	EXPECT_NE(out.find("ATE 0.1"), std::string::npos) << out;
	// The prefix holds every library and tool (hundreds of MB in a sanitizer build): free it.
	if (!::testing::Test::HasFailure()) mrpt::system::deleteFilesInDirectory(dir, true);
}

// The installed tools start and find their shipped data in any prefix: installed, then moved
// elsewhere, run from another folder with the build and source trees hidden (an empty tmpfs
// mounted over them in a private mount namespace, when `unshare` may create one).
TEST(InstalledPackage, ToolsRunFromAMovedPrefixWithoutTheBuildOrSourceTree)
{
	// Outside the source and build trees, so hiding them leaves the prefix in view.
	std::string tmpl = (std::filesystem::temp_directory_path() / "keygrid_install_XXXXXX").string();
	ASSERT_NE(::mkdtemp(tmpl.data()), nullptr) << tmpl;
	const std::string dir = tmpl;
	const std::string build = KEYGRID_TEST_BINARY_DIR, source = keygrid::test::sourceDir();
	std::string out;
	ASSERT_EQ(runCommand("cmake --install " + build + " --prefix " + dir + "/staged", &out), 0) << out;
	const std::string prefix = dir + "/moved";
	ASSERT_EQ(runCommand("mv " + dir + "/staged " + prefix, &out), 0) << out;

	// Nothing in the tools' RUNPATH may point at the build tree or the install location.
	ASSERT_EQ(runCommand("readelf -d " + prefix + "/bin/keygrid-slam | grep -E 'R(UN)?PATH'", &out), 0) << out;
	EXPECT_NE(out.find("$ORIGIN/"), std::string::npos) << out;
	EXPECT_EQ(out.find(build), std::string::npos) << out;
	EXPECT_EQ(out.find(dir), std::string::npos) << out;

	// Render 40 frames with the installed keygrid-sim and one of its shipped scenes, map them with
	// the installed keygrid-slam and configuration (default vocabulary), and start every other tool.
	const std::string bin = prefix + "/bin/", share = prefix + "/share/keygrid";
	const std::string work = dir + "/work";
	const std::string script = dir + "/run_installed.sh";
	{
		std::ofstream f(script);
		f << "set -e\nmkdir -p " << work << "\ncd " << work << "\n"
		  << "if [ -e " << source << "/CMakeLists.txt ] && [ \"$KEYGRID_HIDDEN\" = 1 ]; then echo source tree still in view; exit 90; fi\n"
		  << bin << "keygrid-sim --quiet --scene " << share << "/config/sim/room_loop.ini --frames 40 --output sim"
		  << " --voxel-resolution 0 --floorplan-resolution 0\n"
		  << bin << "keygrid-slam --quiet --config " << share << "/config/sim.ini --input sim/tum --output slam --gt sim/groundtruth.txt\n";
		for (const char* tool : {"keygrid-eval", "keygrid-map", "keygrid-vocab", "keygrid-batch", "keygrid-tum2rawlog"})
			f << bin << tool << " --help >/dev/null\n";
	}
	const bool canHide = runCommand("unshare -rm true") == 0;
	const std::string hide = "mount -t tmpfs none " + source + " && " +
		(build.rfind(source + "/", 0) == 0 ? "" : "mount -t tmpfs none " + build + " && ");
	const std::string cmd = canHide ? "unshare -rm sh -c '" + hide + "KEYGRID_HIDDEN=1 sh " + script + "'" : "sh " + script;
	std::string log;
	ASSERT_EQ(runCommand("env -u LD_LIBRARY_PATH -u LD_PRELOAD -u KEYGRID_SHARE_DIR " + cmd, &log), 0) << cmd << "\n" << log;
	if (!canHide) std::cout << "[ note ] unshare cannot create a mount namespace here: the trees stay in view\n";

	const auto report = nlohmann::json::parse(keygrid::test::readTextFile(work + "/slam/report.json"));
	EXPECT_EQ(report.value("frames", 0), 40);
	EXPECT_EQ(report.value("vocabulary", std::string()), share + "/vocabulary/keygrid_orb_k10_L4.bin");
	// 40 frames of room_loop's first metres: a few millimetres against the renderer's ground truth.
	EXPECT_LT(report.value("ate_rmse_m", 1.0), 0.01) << report.dump(1);
	if (!::testing::Test::HasFailure()) std::filesystem::remove_all(dir);
}
