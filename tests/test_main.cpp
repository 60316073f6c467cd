// gtest entry point shared by every keygrid test executable, plus the TestData helpers.
#include "TestData.h"

#include <mrpt/system/filesystem.h>

#include <array>
#include <fstream>
#include <limits>
#include <regex>
#include <cstdio>
#include <cstdlib>
#include <sys/wait.h>

namespace keygrid::test
{
std::string sourceDir() { return KEYGRID_SOURCE_DIR; }
std::string dataDir() { return sourceDir() + "/tests/data"; }

std::string sharedDataDir()
{
	if (const char* e = std::getenv("KEYGRID_SHARED_DATA"); e && *e) return e;
	return sourceDir() + "/../shared/data";
}

bool haveSharedData(const std::string& sub)
{
	return mrpt::system::directoryExists(sharedDataDir() + (sub.empty() ? "" : "/" + sub));
}

std::string mrptDatasetsDir() { return "/usr/share/mrpt/datasets"; }

std::string toolPath(const std::string& tool) { return std::string(KEYGRID_BINARY_DIR) + "/bin/" + tool; }

std::string scratchDir(const std::string& name)
{
	const std::string d = std::string(KEYGRID_BINARY_DIR) + "/test-scratch/" + name;
	mrpt::system::deleteFilesInDirectory(d, true);
	mrpt::system::createDirectory(std::string(KEYGRID_BINARY_DIR) + "/test-scratch");
	mrpt::system::createDirectory(d);
	return d;
}

std::string readTextFile(const std::string& path)
{
	std::ifstream f(path);
	return {std::istreambuf_iterator<char>(f), {}};
}

double jsonNumber(const std::string& json, const std::string& key)
{
	std::smatch m;
	if (!std::regex_search(json, m, std::regex("\"" + key + "\": ([-0-9.eE+]+)")))
		return std::numeric_limits<double>::quiet_NaN();
	return std::stod(m[1]);
}

int runCommand(const std::string& cmd, std::string* output)
{
	std::string full = cmd + " 2>&1";
	FILE* p = popen(full.c_str(), "r");
	if (!p) return -1;
	std::array<char, 4096> buf{};
	std::string out;
	while (std::fgets(buf.data(), buf.size(), p)) out += buf.data();
	const int st = pclose(p);
	if (output) *output = out;
	return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

}  // namespace keygrid::test

int main(int argc, char** argv)
{
	::testing::InitGoogleTest(&argc, argv);
	return RUN_ALL_TESTS();
}
