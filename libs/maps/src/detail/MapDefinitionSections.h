#pragma once
/** \file MapDefinitionSections.h
 * A map definition's three option structs and their INI sections `<prefix>_creationOpts`,
 * `<prefix>_insertOpts` and `<prefix>_likelihoodOpts` (MRPT's CMultiMetricMap layout): read
 * and dumped in that order by the plugins whose three structs are CLoadableOptions.
 */
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/config/CLoadableOptions.h>

#include <ostream>
#include <string>

namespace keygrid::detail
{
inline void loadMapSections(
	const mrpt::config::CConfigFileBase& source, const std::string& prefix, mrpt::config::CLoadableOptions& creation,
	mrpt::config::CLoadableOptions& insertion, mrpt::config::CLoadableOptions& likelihood)
{
	creation.loadFromConfigFile(source, prefix + "_creationOpts");
	insertion.loadFromConfigFile(source, prefix + "_insertOpts");
	likelihood.loadFromConfigFile(source, prefix + "_likelihoodOpts");
}

inline void dumpMapSections(
	std::ostream& out, const mrpt::config::CLoadableOptions& creation, const mrpt::config::CLoadableOptions& insertion,
	const mrpt::config::CLoadableOptions& likelihood)
{
	creation.dumpToTextStream(out);
	insertion.dumpToTextStream(out);
	likelihood.dumpToTextStream(out);
}

}  // namespace keygrid::detail
