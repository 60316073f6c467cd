// An installed keygrid is usable from another CMake project through find_package(keygrid).
#include "TestData.h"

#include <mrpt/system/filesystem.h>

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
