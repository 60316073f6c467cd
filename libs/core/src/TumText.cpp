#include <keygrid/core/TumText.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace keygrid::core
{
std::vector<TextRecord> readTumTextRecords(const std::string& path)
{
	// A folder opens as a stream that reads nothing: name it instead of reading no lines.
	if (std::filesystem::is_directory(path)) throw std::runtime_error("'" + path + "' is a folder, not a file");
	std::ifstream f(path);
	if (!f) throw std::runtime_error("cannot open '" + path + "'");
	std::vector<TextRecord> out;
	std::string line;
	std::size_t n = 0;
	while (std::getline(f, line))
	{
		++n;
		if (const auto h = line.find('#'); h != std::string::npos) line.resize(h);
		TextRecord rec;
		rec.line = n;
		std::string cur;
		for (char ch : line)
		{
			if (ch == ' ' || ch == '\t' || ch == ',' || ch == '\r')
			{
				if (!cur.empty()) rec.fields.push_back(std::move(cur));
				cur.clear();
			}
			else
				cur.push_back(ch);
		}
		if (!cur.empty()) rec.fields.push_back(std::move(cur));
		if (!rec.fields.empty()) out.push_back(std::move(rec));
	}
	return out;
}

bool parseDouble(const std::string& s, double& out)
{
	if (s.empty()) return false;
	char* end = nullptr;
	out = std::strtod(s.c_str(), &end);
	return end == s.c_str() + s.size() && std::isfinite(out);
}

}  // namespace keygrid::core
