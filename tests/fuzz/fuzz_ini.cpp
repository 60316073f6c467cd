/** \file fuzz_ini.cpp
 * libFuzzer target: any bytes as an INI file: keygrid's line check, then MRPT's parser and
 * keygrid's strict readers on every key of every section.
 */
#include <keygrid/core/ConfigReading.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
	const std::string text(reinterpret_cast<const char*>(data), size);
	try
	{
		keygrid::core::checkIniText(text, "fuzz.ini");
	}
	catch (const std::invalid_argument&)
	{
		return 0;  // refused: MRPT never sees it
	}
	try
	{
		const mrpt::config::CConfigFileMemory ini(text);
		std::vector<std::string> sections;
		ini.getAllSections(sections);
		for (const auto& s : sections)
		{
			std::vector<std::string> keys;
			ini.getAllKeys(s, keys);
			for (const auto& k : keys)
			{
				try
				{
					(void)keygrid::core::readFiniteNumber(ini, s, k, 0.0);
				}
				catch (const std::invalid_argument&)
				{
				}
				try
				{
					(void)keygrid::core::readInteger(ini, s, k, 0, -1000000, 1000000);
				}
				catch (const std::invalid_argument&)
				{
				}
				try
				{
					(void)keygrid::core::readBoolean(ini, s, k, false);
				}
				catch (const std::invalid_argument&)
				{
				}
			}
		}
	}
	catch (const std::exception&)
	{
	}
	return 0;
}
