#include "IniHelpers.h"

#include <keygrid/core/TumText.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace keygrid::sim::ini
{
void fail(const std::string& s, const std::string& k, const std::string& v, const std::string& why)
{
	throw std::invalid_argument("[" + s + "] " + k + " = '" + v + "': " + why);
}

std::string raw(const mrpt::config::CConfigFileBase& c, const std::string& s, const std::string& k)
{
	std::string v = c.read_string(s, k, "", false);
	// Strip trailing comments and whitespace ("5 ; frames" -> "5").
	if (const auto p = v.find_first_of(";#"); p != std::string::npos) v = v.substr(0, p);
	const auto b = v.find_first_not_of(" \t\r");
	const auto e = v.find_last_not_of(" \t\r");
	return b == std::string::npos ? std::string() : v.substr(b, e - b + 1);
}

std::vector<double> numbers(const std::string& s, const std::string& k, const std::string& v)
{
	std::vector<double> out;
	std::istringstream is(v);
	std::string tok;
	while (is >> tok)
	{
		double x = 0;
		if (!core::parseDouble(tok, x)) fail(s, k, v, "'" + tok + "' is not a finite number");
		out.push_back(x);
	}
	return out;
}

double readDouble(
	const mrpt::config::CConfigFileBase& c, const std::string& s, const std::string& k, double def,
	double lo, double hi)
{
	const std::string v = raw(c, s, k);
	if (v.empty()) return def;
	const auto n = numbers(s, k, v);
	if (n.size() != 1) fail(s, k, v, "expected one number");
	if (!(n[0] >= lo && n[0] <= hi))
	{
		std::ostringstream os;
		os << "must be in [" << lo << ", " << hi << "]";
		fail(s, k, v, os.str());
	}
	return n[0];
}

long readInt(
	const mrpt::config::CConfigFileBase& c, const std::string& s, const std::string& k, long def,
	long lo, long hi)
{
	const double x = readDouble(c, s, k, static_cast<double>(def), lo, hi);
	if (x != std::floor(x)) fail(s, k, raw(c, s, k), "expected an integer");
	return static_cast<long>(x);
}

std::uint64_t readSeed(
	const mrpt::config::CConfigFileBase& c, const std::string& s, const std::string& k,
	std::uint64_t def)
{
	const std::string v = raw(c, s, k);
	if (v.empty()) return def;
	std::size_t used = 0;
	unsigned long long x = 0;
	try
	{
		x = std::stoull(v, &used);
	}
	catch (const std::exception&)
	{
		used = 0;
	}
	if (used != v.size() || v[0] == '-') fail(s, k, v, "expected a non-negative integer");
	return x;
}

bool readBool(
	const mrpt::config::CConfigFileBase& c, const std::string& s, const std::string& k, bool def)
{
	const std::string v = raw(c, s, k);
	if (v.empty()) return def;
	if (v == "true" || v == "1" || v == "yes" || v == "on") return true;
	if (v == "false" || v == "0" || v == "no" || v == "off") return false;
	fail(s, k, v, "expected true or false");
}

std::vector<double> readVector(
	const mrpt::config::CConfigFileBase& c, const std::string& s, const std::string& k,
	std::size_t n, const std::vector<double>& def)
{
	const std::string v = raw(c, s, k);
	if (v.empty()) return def;
	auto out = numbers(s, k, v);
	if (out.size() != n) fail(s, k, v, "expected " + std::to_string(n) + " numbers");
	return out;
}

}  // namespace keygrid::sim::ini
