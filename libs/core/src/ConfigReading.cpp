#include <keygrid/core/ConfigReading.h>
#include <keygrid/core/TumText.h>
#include <mrpt/config/CConfigFileBase.h>

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

}  // namespace keygrid::core
