#pragma once
/** \file TestData.h
 * Where tests find their inputs, in the spirit of MRPT's UNITTEST_BASEDIR:
 * - dataDir(): the repository's own tests/data (always present);
 * - sharedDataDir(): ../shared/data (real TUM / ICL sequences; absent on a user's machine:
 *   tests that need it call KEYGRID_SKIP_WITHOUT_SHARED_DATA);
 * - mrptDatasetsDir(): /usr/share/mrpt/datasets (Debian mrpt-common);
 * - toolPath("keygrid-eval"): a built executable;
 * - scratchDir("name"): an empty folder under the build tree for a test's outputs.
 */
#include <gtest/gtest.h>

#include <string>

namespace keygrid::test
{
std::string sourceDir();
std::string dataDir();
std::string sharedDataDir();
bool haveSharedData(const std::string& sub = "");
std::string mrptDatasetsDir();
std::string toolPath(const std::string& tool);
std::string scratchDir(const std::string& name);
/** Whole content of a text file ("" if unreadable). */
std::string readTextFile(const std::string& path);
/** The number after `"key": ` in a JSON text, NaN when absent (so any comparison fails). */
double jsonNumber(const std::string& json, const std::string& key);
/** Runs a shell command, returns its exit status; stdout+stderr go to *output when given. */
int runCommand(const std::string& cmd, std::string* output = nullptr);

}  // namespace keygrid::test

#define KEYGRID_SKIP_WITHOUT_SHARED_DATA(sub)                                             \
	do                                                                                    \
	{                                                                                     \
		if (!keygrid::test::haveSharedData(sub))                                          \
			GTEST_SKIP() << "shared data '" << (sub) << "' not found under "              \
						 << keygrid::test::sharedDataDir() << " (set KEYGRID_SHARED_DATA)"; \
	} while (0)
