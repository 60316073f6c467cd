/** \file BatchExperiment.cpp
 * EXPERIMENT.ini parsing and validation, and configuration overrides (see BatchExperiment.h).
 * The experiment file has its own small reader (not MRPT's) so that errors carry line numbers,
 * duplicate keys are caught and sections keep their order (the table rows follow it).
 */
#include <keygrid/core/ConfigReading.h>
#include <keygrid/slam/IniReference.h>
#include <keygrid/slam/apps/BatchExperiment.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/system/filesystem.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

namespace keygrid::slam
{
namespace
{
std::string trim(const std::string& s) { return core::trimBlanks(s); }

std::string lower(std::string s)
{
	std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
	return s;
}

bool isComment(const std::string& trimmed)
{
	return trimmed.empty() || trimmed[0] == '#' || trimmed[0] == ';' || trimmed.rfind("//", 0) == 0;
}

struct Entry
{
	std::string key, value;
	int line{0};
};
struct Section
{
	std::string name;
	int line{0};
	std::vector<Entry> entries;
};

std::vector<Section> parseIni(const std::string& text, const std::string& origin)
{
	std::vector<Section> sections;
	std::istringstream in(text);
	int n = 0;
	for (std::string raw; std::getline(in, raw);)
	{
		n++;
		const std::string line = trim(raw);
		if (isComment(line)) continue;
		const std::string at = origin + ":" + std::to_string(n) + ": ";
		if (line.front() == '[')
		{
			if (line.back() != ']') throw std::invalid_argument(at + "'" + line + "' is not a [section] line");
			const std::string name = trim(line.substr(1, line.size() - 2));
			for (const auto& s : sections)
				if (s.name == name) throw std::invalid_argument(at + "section [" + name + "] appears twice (first at line " + std::to_string(s.line) + ")");
			sections.push_back({name, n, {}});
			continue;
		}
		const auto eq = line.find('=');
		if (eq == std::string::npos) throw std::invalid_argument(at + "'" + line + "' is not a key = value line");
		if (sections.empty()) throw std::invalid_argument(at + "key outside of any [section]");
		Entry e{trim(line.substr(0, eq)), trim(line.substr(eq + 1)), n};
		for (const auto& o : sections.back().entries)
			if (o.key == e.key)
				throw std::invalid_argument(at + "[" + sections.back().name + "] " + e.key + " appears twice (first at line " + std::to_string(o.line) + ")");
		sections.back().entries.push_back(e);
	}
	return sections;
}

/** Reads the typed values of one section, rejecting keys it does not know. */
class SectionReader
{
   public:
	SectionReader(const Section& s, const std::string& origin, std::set<std::string> known)
		: m_s(s), m_origin(origin)
	{
		for (const auto& e : s.entries)
			if (!known.count(e.key)) fail(e, "unknown key (expected one of: " + join(known) + ")");
	}
	const Entry* find(const std::string& key) const
	{
		for (const auto& e : m_s.entries)
			if (e.key == key) return &e;
		return nullptr;
	}
	std::string str(const std::string& key, const std::string& def = "") const
	{
		const Entry* e = find(key);
		if (!e) return def;
		if (e->value.empty()) fail(*e, "empty value");
		return e->value;
	}
	std::optional<long> integer(const std::string& key, long lo, long hi) const
	{
		const Entry* e = find(key);
		if (!e) return std::nullopt;
		double v = 0;
		if (!core::parseTrimmedDouble(e->value, v) || v != std::floor(v) || v < lo || v > hi)
			fail(*e, "'" + e->value + "' is not an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
		return static_cast<long>(v);
	}
	std::optional<double> number(const std::string& key, double lo) const
	{
		const Entry* e = find(key);
		if (!e) return std::nullopt;
		double v = 0;
		if (!core::parseTrimmedDouble(e->value, v) || v < lo) fail(*e, "'" + e->value + "' is not a number >= " + std::to_string(lo));
		return v;
	}
	[[noreturn]] void fail(const Entry& e, const std::string& why) const
	{
		throw std::invalid_argument(m_origin + ":" + std::to_string(e.line) + ": [" + m_s.name + "] " + e.key + ": " + why);
	}
	[[noreturn]] void failSection(const std::string& why) const
	{
		throw std::invalid_argument(m_origin + ":" + std::to_string(m_s.line) + ": [" + m_s.name + "] " + why);
	}

   private:
	const Section& m_s;
	std::string m_origin;
	static std::string join(const std::set<std::string>& s)
	{
		std::string o;
		for (const auto& x : s) o += (o.empty() ? "" : ", ") + x;
		return o;
	}
};

/** "MappingApplication_<map>_<NN><suffix>" -> {map, suffix} (e.g. {"octoMap", "_insertOpts"}). */
std::optional<std::pair<std::string, std::string>> splitMapSection(const std::string& section)
{
	const std::string prefix = "mappingapplication_";
	if (lower(section).rfind(prefix, 0) != 0) return std::nullopt;
	const std::string rest = section.substr(prefix.size());
	auto digit = [&](std::size_t i) { return i < rest.size() && std::isdigit(static_cast<unsigned char>(rest[i])); };
	for (std::size_t p = 1; p + 2 < rest.size(); p++)
		if (rest[p] == '_' && digit(p + 1) && digit(p + 2) && (p + 3 == rest.size() || rest[p + 3] == '_'))
			return std::make_pair(rest.substr(0, p), rest.substr(p + 3));
	return std::nullopt;
}

/** Dataset and config names become folder names. */
bool validName(const std::string& n)
{
	if (n.empty() || !std::isalnum(static_cast<unsigned char>(n[0]))) return false;
	return std::all_of(n.begin(), n.end(), [](unsigned char c) { return std::isalnum(c) || c == '_' || c == '-' || c == '.'; });
}
}  // namespace

ExperimentSpec ExperimentSpec::FromText(const std::string& text, const std::string& origin)
{
	ExperimentSpec spec;
	bool haveBatch = false;
	for (const Section& s : parseIni(text, origin))
	{
		if (s.name == "batch")
		{
			haveBatch = true;
			SectionReader r(s, origin, {"output", "jobs", "repeats", "title", "timeout"});
			spec.batch.output = r.str("output");
			spec.batch.jobs = static_cast<int>(r.integer("jobs", 1, 64).value_or(spec.batch.jobs));
			spec.batch.repeats = static_cast<int>(r.integer("repeats", 1, 1000).value_or(spec.batch.repeats));
			spec.batch.title = r.str("title");
			spec.batch.timeoutSeconds = r.number("timeout", 0).value_or(0);
			continue;
		}
		const auto dot = s.name.find('.');
		const std::string kind = s.name.substr(0, dot), name = dot == std::string::npos ? "" : s.name.substr(dot + 1);
		if ((kind == "dataset" || kind == "config") && !validName(name))
			throw std::invalid_argument(origin + ":" + std::to_string(s.line) + ": [" + s.name + "]: the name must be letters, digits, '_', '-' or '.', starting with a letter or digit");
		if (kind == "dataset")
		{
			SectionReader r(s, origin, {"input", "gt", "scene", "seed", "frames", "set", "max_frames"});
			DatasetSpec d;
			d.name = name;
			d.input = r.str("input");
			d.gt = r.str("gt");
			d.scene = r.str("scene");
			d.seed = r.integer("seed", 0, 4294967295L);
			d.frames = r.integer("frames", 1, 10000000L);
			d.simSet = r.str("set");
			if (!d.simSet.empty())
			{
				try
				{
					parseOverrides(d.simSet, "set");  // syntax now; keygrid-sim checks the keys
				}
				catch (const std::invalid_argument& ex)
				{
					r.fail(*r.find("set"), ex.what());
				}
			}
			d.maxFrames = r.integer("max_frames", 0, 10000000L).value_or(0);
			if (d.input.empty() == d.scene.empty()) r.failSection("needs exactly one of input = (a recorded sequence) or scene = (keygrid-sim generates it)");
			if (!d.generated() && (d.seed || d.frames || !d.simSet.empty()))
				r.fail(*r.find(d.seed ? "seed" : d.frames ? "frames" : "set"), "only with scene = (keygrid-sim options)");
			if (d.generated() && !mrpt::system::fileExists(d.scene)) r.fail(*r.find("scene"), "file '" + d.scene + "' does not exist");
			spec.datasets.push_back(d);
		}
		else if (kind == "config")
		{
			SectionReader r(s, origin, {"file", "set"});
			ConfigSpec c;
			c.name = name;
			c.file = r.str("file");
			if (c.file.empty()) r.failSection("needs file = (a keygrid-slam INI)");
			if (!mrpt::system::fileExists(c.file)) r.fail(*r.find("file"), "file '" + c.file + "' does not exist");
			if (const Entry* e = r.find("set"))
			{
				try
				{
					c.overrides = parseOverrides(e->value, "set");
				}
				catch (const std::invalid_argument& ex)
				{
					r.fail(*e, ex.what());
				}
			}
			spec.configs.push_back(c);
		}
		else
			throw std::invalid_argument(origin + ":" + std::to_string(s.line) + ": unknown section [" + s.name + "] (expected [batch], [dataset.NAME] or [config.NAME])");
	}
	if (!haveBatch) throw std::invalid_argument(origin + ": no [batch] section");
	if (spec.datasets.empty()) throw std::invalid_argument(origin + ": no [dataset.NAME] section");
	if (spec.configs.empty()) throw std::invalid_argument(origin + ": no [config.NAME] section");
	return spec;
}

ExperimentSpec ExperimentSpec::FromFile(const std::string& path)
{
	if (!mrpt::system::fileExists(path)) throw std::invalid_argument("experiment file '" + path + "' does not exist");
	ExperimentSpec s = FromText(mrpt::io::file_get_contents(path), path);
	s.path = path;
	if (s.batch.title.empty()) s.batch.title = mrpt::system::extractFileName(path);
	return s;
}

std::vector<ConfigOverride> parseOverrides(const std::string& text, const std::string& where)
{
	std::vector<ConfigOverride> out;
	std::istringstream in(text);
	for (std::string item; std::getline(in, item, ';');)
	{
		item = trim(item);
		if (item.empty()) continue;
		const auto eq = item.find('=');
		const std::string lhs = trim(item.substr(0, eq));
		const auto dot = lhs.rfind('.');
		if (eq == std::string::npos || dot == std::string::npos || dot == 0 || dot + 1 == lhs.size())
			throw std::invalid_argument(where + ": '" + item + "' is not section.key=value");
		out.push_back({trim(lhs.substr(0, dot)), trim(lhs.substr(dot + 1)), trim(item.substr(eq + 1))});
	}
	if (out.empty()) throw std::invalid_argument(where + ": no section.key=value given");
	return out;
}

std::string applyOverrides(const std::string& iniText, const std::vector<ConfigOverride>& overrides)
{
	std::vector<std::string> lines;
	{
		std::istringstream in(iniText);
		for (std::string l; std::getline(in, l);) lines.push_back(l);
	}
	auto sectionOf = [](const std::string& t) { return lower(trim(t.substr(1, t.size() - 2))); };
	for (const auto& o : overrides)
	{
		const std::string sec = lower(o.section), key = lower(o.key), line = o.key + " = " + o.value;
		// The section's first line, and the end of its last non-blank line.
		std::optional<std::size_t> begin, lastContent;
		bool done = false;
		for (std::size_t i = 0; i < lines.size() && !done; i++)
		{
			const std::string t = trim(lines[i]);
			if (!t.empty() && t.front() == '[' && t.back() == ']')
			{
				if (begin) break;  // the next section starts
				if (sectionOf(t) == sec) begin = lastContent = i;
				continue;
			}
			if (!begin) continue;
			if (!t.empty()) lastContent = i;
			if (isComment(t)) continue;
			const auto eq = t.find('=');
			if (eq != std::string::npos && lower(trim(t.substr(0, eq))) == key)
			{
				lines[i] = line;
				done = true;
			}
		}
		if (done) continue;
		if (begin)
			lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(*lastContent + 1), line);
		else
		{
			if (!lines.empty() && !trim(lines.back()).empty()) lines.push_back("");
			lines.push_back("[" + o.section + "]");
			lines.push_back(line);
		}
	}
	std::string out;
	for (const auto& l : lines) out += l + "\n";
	return out;
}

void checkOverrideKeys(const std::string& iniText, const std::vector<ConfigOverride>& overrides, const std::string& where)
{
	// Keys present in the file itself (MRPT reads any of them).
	std::set<std::pair<std::string, std::string>> inFile;
	{
		std::istringstream in(iniText);
		std::string sec;
		for (std::string raw; std::getline(in, raw);)
		{
			const std::string t = trim(raw);
			if (isComment(t)) continue;
			if (t.front() == '[' && t.back() == ']')
				sec = lower(trim(t.substr(1, t.size() - 2)));
			else if (const auto eq = t.find('='); eq != std::string::npos)
				inFile.insert({sec, lower(trim(t.substr(0, eq)))});
		}
	}
	auto hasKey = [](const std::vector<IniSection>& secs, const std::string& sec, const std::string& key) {
		for (const auto& s : secs)
			if (lower(s.name) == sec)
				for (const auto& k : s.keys)
					if (lower(k.key) == key) return true;
		return false;
	};
	const auto slamDefaults = slamConfigReference();
	for (const auto& o : overrides)
	{
		const std::string sec = lower(o.section), key = lower(o.key);
		if (inFile.count({sec, key}) || hasKey(slamDefaults, sec, key)) continue;
		if (sec == "mappingapplication" && key.size() > 6 && key.substr(key.size() - 6) == "_count" &&
			mapPluginReference(o.key.substr(0, o.key.size() - 6)))
			continue;
		if (const auto map = splitMapSection(o.section))
			if (const auto ref = mapPluginReference(map->first))
				if (hasKey(*ref, lower("MappingApplication_" + map->first + "_00" + map->second), key)) continue;
		throw std::invalid_argument(
			where + ": unknown key " + o.section + "." + o.key +
			" (in neither the configuration file nor keygrid-slam's options: see doc/ini-reference.md)");
	}
}

}  // namespace keygrid::slam
