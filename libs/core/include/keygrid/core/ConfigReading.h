#pragma once
/** \file ConfigReading.h
 * Strict reading of numbers from INI files: the value must be a whole finite number, or the
 * error names section, key and value. (MRPT's read_double() silently turns garbage into 0.)
 */
#include <string>

namespace mrpt::config
{
class CConfigFileBase;
}

namespace keygrid::core
{
/** `key` of `section` as a finite number; a missing key keeps `current`. Surrounding blanks are
 * ignored. Throws std::invalid_argument("[section] key = 'value' is not a finite number"). */
double readFiniteNumber(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section, const std::string& key,
	double current);

/** `text` without leading and trailing blanks (space, tab, CR, LF). */
std::string trimBlanks(const std::string& text);

/** Trims blanks and parses a whole finite number (core::parseDouble after trimming). */
bool parseTrimmedDouble(const std::string& text, double& out);

}  // namespace keygrid::core
