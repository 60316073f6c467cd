#include <keygrid/loop/DataFiles.h>
#include <mrpt/system/filesystem.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace keygrid::loop
{
namespace
{
/** <folder of the running executable>/<bindir -> datadir/keygrid>, "" when unknown. An installed
 * tool finds its data this way in any prefix, also one moved after installation. */
std::string besideExecutable()
{
	std::error_code ec;
	const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
	if (ec || exe.empty()) return {};
	return (exe.parent_path() / KEYGRID_BIN_TO_SHARE_DIR).lexically_normal().string();
}
}  // namespace

std::vector<std::string> dataDirectories()
{
	std::vector<std::string> dirs;
	if (const char* env = std::getenv("KEYGRID_SHARE_DIR"); env && *env) dirs.emplace_back(env);
	if (auto beside = besideExecutable(); !beside.empty()) dirs.push_back(std::move(beside));
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

}  // namespace keygrid::loop
