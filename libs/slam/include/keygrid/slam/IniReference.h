#pragma once
/** \file IniReference.h
 * doc/ini-reference.md, generated from the options structs themselves (`keygrid-slam
 * --ini-reference`): every key of the effective default configuration (what
 * SlamConfig::saveToConfigFile writes, with the comments it passes to MRPT's write()), and the
 * creation / insertion / likelihood options of every keygrid map plugin registered with MRPT's
 * map factory (TMetricMapTypesRegistry), looked up by its INI name.
 */
#include <optional>
#include <string>
#include <vector>

namespace keygrid::slam
{
/** One INI key: its default as written by saveToConfigFile and the comment that came with it. */
struct IniKey
{
	std::string key, defaultValue, description;
};

struct IniSection
{
	std::string name;
	std::vector<IniKey> keys;  //!< in the order the options struct writes them
};

/** The sections of SlamConfig's defaults, in the order saveToConfigFile writes them.
 * `tidyNumbers`: "3.000000" as "3" (for people); false keeps what MRPT's write() made of each
 * type (a double always has a decimal point, an integer never). */
std::vector<IniSection> slamConfigReference(bool tidyNumbers = true);

/** The INI names (e.g. "ismOccupancyGrid2D") of every keygrid map class registered with MRPT's
 * map factory, sorted. */
std::vector<std::string> keygridMapPluginNames();

/** Sections `MappingApplication_<mapName>_00_*` of a map type registered with MRPT's factory,
 * with the defaults of its TMapDefinition; std::nullopt when no map of that name is registered.
 */
std::optional<std::vector<IniSection>> mapPluginReference(const std::string& mapName);

/** The whole markdown document (doc/ini-reference.md). Deterministic: no dates, no paths. */
std::string iniReferenceMarkdown();

}  // namespace keygrid::slam
