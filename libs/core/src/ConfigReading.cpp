#include <keygrid/core/ConfigReading.h>
#include <keygrid/core/TumText.h>
#include <mrpt/config/CConfigFileBase.h>

#include <algorithm>
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

void checkIniText(const std::string& text, const std::string& origin)
{
	if (text.find('\0') != std::string::npos) throw std::invalid_argument(origin + ": not a text file (it holds NUL bytes)");
	std::size_t begin = 0, lineNo = 0;
	while (begin <= text.size())
	{
		const std::size_t end = std::min(text.find('\n', begin), text.size());
		const std::string line = trimBlanks(text.substr(begin, end - begin));
		++lineNo;
		begin = end + 1;
		if (line.empty() || line[0] == '#' || line[0] == ';' || line.compare(0, 2, "//") == 0 || line[0] == '@') continue;
		if (line[0] == '[')
		{
			if (line.back() == ']' && line.size() > 2) continue;
			throw std::invalid_argument(origin + ":" + std::to_string(lineNo) + ": '" + line + "' is not a [section] line");
		}
		const auto eq = line.find('=');
		if (eq != std::string::npos && !trimBlanks(line.substr(0, eq)).empty()) continue;
		throw std::invalid_argument(
			origin + ":" + std::to_string(lineNo) + ": '" + line.substr(0, 60) + "' is not a [section], a key = value or a comment");
	}
}

namespace
{
/** A whole number of at most 18 digits (no key's range is wider, and it cannot overflow). */
bool parseWholeNumber(const std::string& text, long long& out)
{
	const std::string v = trimBlanks(text);
	const std::size_t sign = (!v.empty() && (v[0] == '-' || v[0] == '+')) ? 1 : 0;
	if (v.size() <= sign || v.size() - sign > 18 || v.find_first_not_of("0123456789", sign) != std::string::npos) return false;
	out = std::stoll(v);
	return true;
}
}  // namespace

long long readInteger(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section, const std::string& key,
	long long current, long long min, long long max)
{
	const std::string raw = cfg.read_string(section, key, "", false);
	if (raw.empty()) return current;
	const auto range = "[" + std::to_string(min) + ", " + std::to_string(max) + "]";
	long long out = 0;
	if (!parseWholeNumber(raw, out))
		throw std::invalid_argument("[" + section + "] " + key + " = '" + raw + "' is not a whole number in " + range);
	if (out < min || out > max)
		throw std::invalid_argument("[" + section + "] " + key + " = " + trimBlanks(raw) + " is out of range " + range);
	return out;
}

long long readWholeNumber(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section, const std::string& key, long long current)
{
	const std::string raw = cfg.read_string(section, key, "", false);
	if (raw.empty()) return current;
	long long out = 0;
	if (!parseWholeNumber(raw, out)) throw std::invalid_argument("[" + section + "] " + key + " = '" + raw + "' is not a whole number");
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
