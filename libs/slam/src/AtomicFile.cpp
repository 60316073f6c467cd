#include <keygrid/slam/AtomicFile.h>

#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace keygrid::slam
{
void writeFileAtomically(const std::string& path, const std::string& content)
{
	const std::string tmp = path + ".tmp";
	{
		std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
		if (!f) throw std::runtime_error("cannot write '" + path + "'");
		f << content;
		f.flush();
		if (!f)
		{
			std::remove(tmp.c_str());
			throw std::runtime_error("error while writing '" + path + "'");
		}
	}
	if (std::rename(tmp.c_str(), path.c_str()) != 0)
	{
		std::remove(tmp.c_str());
		throw std::runtime_error("cannot rename '" + tmp + "' to '" + path + "'");
	}
}

}  // namespace keygrid::slam
