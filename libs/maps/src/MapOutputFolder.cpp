/** \file MapOutputFolder.cpp
 * MapOutputFolder: one file at a time, failures collected.
 */
#include <keygrid/maps/MapOutputFolder.h>

#include <exception>
#include <stdexcept>

namespace keygrid::maps
{
bool MapOutputFolder::write(const std::string& name, const std::function<void(const std::string& path)>& write)
{
	try
	{
		write(m_dir + "/" + name);
		m_files.push_back(name);
		return true;
	}
	catch (const std::exception& e)
	{
		if (m_firstError.empty()) m_firstError = e.what();
		m_failures++;
		return false;
	}
}

void MapOutputFolder::throwIfAnyFailed() const
{
	if (m_firstError.empty()) return;
	std::string what = m_firstError;
	if (m_failures > 1) what += " (and " + std::to_string(m_failures - 1) + " more map files not written)";
	throw std::runtime_error(what);
}

}  // namespace keygrid::maps
