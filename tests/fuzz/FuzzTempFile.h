#pragma once
/** \file FuzzTempFile.h
 * The readers under test take file names: each fuzz input is written to one file per process
 * (under $TMPDIR), rewritten for every input.
 */
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace keygrid::fuzz
{
/** `<$TMPDIR or /tmp>/keygrid_fuzz_<pid>/<name>`, its folder created on first use. */
inline std::string scratchPath(const std::string& name)
{
	static const std::string dir = [] {
		const char* t = std::getenv("TMPDIR");
		return std::string(t && *t ? t : "/tmp") + "/keygrid_fuzz_" + std::to_string(::getpid());
	}();
	const std::filesystem::path p = std::filesystem::path(dir) / name;
	std::filesystem::create_directories(p.parent_path());
	return p.string();
}

inline std::string writeInput(const std::string& name, const std::uint8_t* data, std::size_t size)
{
	const std::string path = scratchPath(name);
	std::ofstream f(path, std::ios::binary | std::ios::trunc);
	f.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
	if (!f) std::abort();
	return path;
}

}  // namespace keygrid::fuzz
