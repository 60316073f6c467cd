#include <keygrid/slam/DataFiles.h>
#include <mrpt/system/filesystem.h>

#include <cstdlib>
#include <stdexcept>

namespace keygrid::slam
{
std::vector<std::string> dataDirectories()
{
	std::vector<std::string> dirs;
	if (const char* env = std::getenv("KEYGRID_SHARE_DIR"); env && *env) dirs.emplace_back(env);
	dirs.emplace_back(KEYGRID_SOURCE_SHARE_DIR);
	dirs.emplace_back(KEYGRID_INSTALL_SHARE_DIR);
	return dirs;
}

std::string findDataFile(const std::string& relative)
{
	std::string searched;
	for (const auto& d : dataDirectories())
	{
		const std::string p = d + "/" + relative;
		if (mrpt::system::fileExists(p)) return p;
		searched += (searched.empty() ? "" : ", ") + d;
	}
	throw std::runtime_error("data file '" + relative + "' not found in " + searched + " (set KEYGRID_SHARE_DIR to the folder holding it)");
}

}  // namespace keygrid::slam
