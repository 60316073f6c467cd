#pragma once
/** \file MapIniChecks.h
 * Shared check of the map plugins' INI sections: a bad value throws naming section and key.
 */
#include <mrpt/config/CConfigFileMemory.h>

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace keygrid::test
{
/** For each (section suffix, "key = value") line, loading a fresh `Definition` (a map's
 * TMapDefinition) from `[prefix<suffix>]` holding only that line throws std::invalid_argument
 * whose message names "[prefix<suffix>] key = ". */
template <class Definition>
void expectBadValuesNameSectionAndKey(const std::string& prefix, const std::vector<std::pair<std::string, std::string>>& lines)
{
	for (const auto& [suffix, line] : lines)
	{
		const std::string section = prefix + suffix, key = line.substr(0, line.find(' '));
		const mrpt::config::CConfigFileMemory ini("[" + section + "]\n" + line + "\n");
		// The definition itself, not TSetOfMetricMapInitializers, which leaks the initializer it
		// was filling when loading throws.
		Definition def;
		try
		{
			def.loadFromConfigFile(ini, prefix);
			ADD_FAILURE() << "[" << section << "] " << line << " accepted";
		}
		catch (const std::invalid_argument& e)
		{
			EXPECT_NE(std::string(e.what()).find("[" + section + "] " + key + " = "), std::string::npos) << e.what();
		}
	}
}

}  // namespace keygrid::test
