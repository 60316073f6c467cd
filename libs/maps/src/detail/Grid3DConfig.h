#pragma once
/** \file Grid3DConfig.h
 * Private helpers of the 3D grid options: strict INI number parsing and range errors that name
 * the key and the offending value.
 */
#include <keygrid/core/ConfigReading.h>
#include <mrpt/config/CConfigFileBase.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace keygrid::detail
{
/** Reads `key` from `section` as a finite number; missing keeps `current`; anything that is not
 * a number throws std::invalid_argument("[section] key = 'value' ..."). */
inline double readNumber(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section, const std::string& key,
	double current)
{
	return core::readFiniteNumber(cfg, section, key, current);
}

/** Reads a boolean (true/false/1/0/yes/no); anything else throws naming key and value. */
inline bool readBool(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section, const std::string& key,
	bool current)
{
	const std::string v = cfg.read_string(section, key, "", false);
	if (v.empty()) return current;
	if (v == "1" || v == "true" || v == "yes" || v == "TRUE" || v == "True") return true;
	if (v == "0" || v == "false" || v == "no" || v == "FALSE" || v == "False") return false;
	throw std::invalid_argument("[" + section + "] " + key + " = '" + v + "' is not a boolean");
}

/** Throws std::invalid_argument("key = value: must be <what>") unless ok. */
inline void require(bool ok, const std::string& key, double value, const std::string& what)
{
	if (!ok)
		throw std::invalid_argument(key + " = " + std::to_string(value) + ": must be " + what);
}

/** Writes a number with full precision (%.17g), as a plain `key = value` line. (MRPT's padded
 * write(section, key, value, w1, w2, comment) stores the padding in the key of in-memory
 * configs, so those cannot be read back.) */
inline void writeNumber(
	mrpt::config::CConfigFileBase& cfg, const std::string& section, const std::string& key,
	double v)
{
	char buf[64];
	std::snprintf(buf, sizeof(buf), "%.17g", v);
	cfg.write(section, key, std::string(buf));
}
inline void writeBool(
	mrpt::config::CConfigFileBase& cfg, const std::string& section, const std::string& key, bool v)
{
	cfg.write(section, key, std::string(v ? "true" : "false"));
}

}  // namespace keygrid::detail
