#pragma once
// Private helpers: typed INI reads that throw naming "[section] key = 'value'" on bad input.
#include <mrpt/config/CConfigFileBase.h>

#include <cstdint>
#include <string>
#include <vector>

namespace keygrid::sim::ini
{
/** Raw string value, or "" when absent. */
std::string raw(const mrpt::config::CConfigFileBase& c, const std::string& s, const std::string& k);
/** Parses all whitespace-separated numbers of a value; throws naming the key on garbage. */
std::vector<double> numbers(const std::string& s, const std::string& k, const std::string& v);

double readDouble(
	const mrpt::config::CConfigFileBase& c, const std::string& s, const std::string& k, double def,
	double lo, double hi);
long readInt(
	const mrpt::config::CConfigFileBase& c, const std::string& s, const std::string& k, long def,
	long lo, long hi);
std::uint64_t readSeed(
	const mrpt::config::CConfigFileBase& c, const std::string& s, const std::string& k,
	std::uint64_t def);
bool readBool(
	const mrpt::config::CConfigFileBase& c, const std::string& s, const std::string& k, bool def);
/** Exactly n numbers (n > 0), or `def` when the key is absent. */
std::vector<double> readVector(
	const mrpt::config::CConfigFileBase& c, const std::string& s, const std::string& k,
	std::size_t n, const std::vector<double>& def);

[[noreturn]] void fail(
	const std::string& s, const std::string& k, const std::string& v, const std::string& why);

}  // namespace keygrid::sim::ini
