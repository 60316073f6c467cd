#include <keygrid/core/ConfigReading.h>
#include <keygrid/core/TumText.h>
#include <mrpt/config/CConfigFileBase.h>

#include <cctype>
#include <stdexcept>

namespace keygrid::core
{
std::string trimBlanks(const std::string& text)
{
	const auto b = text.find_first_not_of(" \t\r\n");
	if (b == std::string::npos) return "";
	const auto e = text.find_last_not_of(" \t\r\n");
	return text.substr(b, e - b + 1);
}

bool parseTrimmedDouble(const std::string& text, double& out)
{
	const std::string t = trimBlanks(text);
	return !t.empty() && parseDouble(t, out);
}

double readFiniteNumber(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section, const std::string& key,
	double current)
{
	const std::string v = cfg.read_string(section, key, "", false);
	if (v.empty()) return current;
	double out = 0;
	if (!parseTrimmedDouble(v, out))
		throw std::invalid_argument("[" + section + "] " + key + " = '" + v + "' is not a finite number");
	return out;
}

long long readInteger(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section, const std::string& key,
	long long current, long long min, long long max)
{
	const std::string raw = cfg.read_string(section, key, "", false);
	if (raw.empty()) return current;
	const std::string v = trimBlanks(raw);
	const auto range = "[" + std::to_string(min) + ", " + std::to_string(max) + "]";
	std::size_t digits = (!v.empty() && (v[0] == '-' || v[0] == '+')) ? 1 : 0;
	const bool wellFormed = v.size() > digits && v.find_first_not_of("0123456789", digits) == std::string::npos;
	// More than 18 digits cannot be in any range a key has (and would overflow).
	if (!wellFormed || v.size() - digits > 18)
		throw std::invalid_argument("[" + section + "] " + key + " = '" + raw + "' is not a whole number in " + range);
	const long long out = std::stoll(v);
	if (out < min || out > max)
		throw std::invalid_argument("[" + section + "] " + key + " = " + v + " is out of range " + range);
	return out;
}

bool readBoolean(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section, const std::string& key,
	bool current)
{
	const std::string raw = cfg.read_string(section, key, "", false);
	if (raw.empty()) return current;
	std::string v = trimBlanks(raw);
	for (auto& ch : v) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
	if (v == "true" || v == "1") return true;
	if (v == "false" || v == "0") return false;
	throw std::invalid_argument("[" + section + "] " + key + " = '" + raw + "' is not a boolean (true, false, 1 or 0)");
}

}  // namespace keygrid::core
