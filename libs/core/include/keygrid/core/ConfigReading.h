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

/** `key` of `section` as a whole number in [min, max] (no fraction, exponent or trailing
 * text: "1000abc", "40.0.0", "1e3", "forty" are refused); a missing key keeps `current`.
 * Throws std::invalid_argument naming section, key, value and the range. */
long long readInteger(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section, const std::string& key,
	long long current, long long min, long long max);

/** readInteger without a range (its reader checks it): at most 18 digits. */
long long readWholeNumber(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section, const std::string& key, long long current);

/** `key` of `section` as a boolean: true/false/1/0 only (any letter case); a missing key keeps
 * `current`. Throws std::invalid_argument naming section, key and value ("maybe"). */
bool readBoolean(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section, const std::string& key,
	bool current);

/** Throws std::invalid_argument("<origin>:<line>: ...") unless every line of an INI text is
 * blank, a comment (#, ; or //), a [section], a key = value or an MRPT directive (@...):
 * MRPT's reader skips any other line silently (an unclosed "[tracker", a binary file). */
void checkIniText(const std::string& text, const std::string& origin);

/** `text` without leading and trailing blanks (space, tab, CR, LF). */
std::string trimBlanks(const std::string& text);

/** Trims blanks and parses a whole finite number (core::parseDouble after trimming). */
bool parseTrimmedDouble(const std::string& text, double& out);

}  // namespace keygrid::core
