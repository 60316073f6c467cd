/** \file IniReference.cpp
 * Generates doc/ini-reference.md from the options structs (see IniReference.h).
 *
 * SlamConfig is written into a recording CConfigFileBase, which keeps every write() in order
 * with its comment. Map plugins are only reachable through MRPT's generic factory
 * (TMetricMapInitializer*), which exposes no per-section save: their sections are recovered by
 * loading the definition from a recording config (which answers every read with the default it
 * is given, and so learns which key each section holds), and their defaults and comments from
 * the definition's dumpToTextStream() (the options' saveToConfigFile output).
 */
#include <keygrid/core/ConfigReading.h>
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <keygrid/slam/IniReference.h>
#include <keygrid/slam/SlamConfig.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/maps/TMetricMapInitializer.h>
#include <mrpt/maps/TMetricMapTypesRegistry.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <sstream>

namespace keygrid::slam
{
namespace
{
std::string trim(const std::string& s) { return core::trimBlanks(s); }

/** MRPT's write(..., comment) stores `value // comment` as the value text. */
IniKey splitValueAndComment(const std::string& key, const std::string& text)
{
	IniKey k;
	k.key = trim(key);
	const auto c = text.find(" // ");
	k.defaultValue = trim(c == std::string::npos ? text : text.substr(0, c));
	if (c != std::string::npos) k.description = trim(text.substr(c + 4));
	return k;
}

/** Collects writes (section, key, value, comment) and reads (section, key, default) in order. */
class RecordingConfig : public mrpt::config::CConfigFileBase
{
   public:
	using mrpt::config::CConfigFileBase::writeString;

	/** Sections reported as existing (some loaders skip sections that do not exist). */
	std::vector<std::string> existingSections;
	std::vector<IniSection> written;
	// readString() is const in MRPT's interface; what was read is not part of the config's state.
	mutable std::vector<IniSection> read;

	void getAllSections(std::vector<std::string>& sections) const override { sections = existingSections; }
	void getAllKeys(const std::string&, std::vector<std::string>& keys) const override { keys.clear(); }
	void clear() override
	{
		written.clear();
		read.clear();
	}

   protected:
	void writeString(const std::string& section, const std::string& name, const std::string& str) override
	{
		add(written, section, splitValueAndComment(name, str));
	}
	std::string readString(
		const std::string& section, const std::string& name, const std::string& defaultStr,
		bool /*failIfNotFound*/) const override
	{
		IniKey k;
		k.key = name;
		k.defaultValue = defaultStr;
		add(read, section, k);
		return defaultStr;
	}

   private:
	static void add(std::vector<IniSection>& list, const std::string& section, const IniKey& k)
	{
		IniSection* s = nullptr;
		for (auto& x : list)
			if (x.name == section) s = &x;
		if (!s)
		{
			list.push_back({section, {}});
			s = &list.back();
		}
		for (auto& existing : s->keys)
			if (existing.key == k.key)
			{
				existing = k;  // written (or read) twice: the last one counts
				return;
			}
		s->keys.push_back(k);
	}
};

/** A number as written ("1.200000", "0.10000000000000001", a float's "0.85000002384185791") in
 * its shortest form that reads back to the same double, or float ("1.2", "0.1", "0.85"); any
 * other text unchanged. */
std::string tidyNumber(const std::string& s)
{
	if (s.empty()) return s;
	char* end = nullptr;
	const double v = std::strtod(s.c_str(), &end);
	if (end == s.c_str() || *end != '\0' || !std::isfinite(v)) return s;
	char b[64];
	if (v == std::floor(v) && std::abs(v) < 1e15)
	{
		std::snprintf(b, sizeof(b), "%.0f", v);
		return b;
	}
	for (int p = 1; p <= 17; p++)
	{
		std::snprintf(b, sizeof(b), "%.*g", p, v);
		const double back = std::strtod(b, nullptr);
		if (back == v || static_cast<float>(back) == static_cast<float>(v)) break;
	}
	return b;
}

/** What the options of keygrid's own map types write (section, key, value, comment), through
 * their saveToConfigFile; false for other types (their defaults come from dumpToTextStream). */
bool saveKnownMapDefinition(const mrpt::maps::TMetricMapInitializer& def, const std::string& prefix, RecordingConfig& rec)
{
	const std::string creation = prefix + "_creationOpts", insert = prefix + "_insertOpts", likelihood = prefix + "_likelihoodOpts";
	if (const auto* d = dynamic_cast<const CISMOccupancyGrid2D::TMapDefinition*>(&def))
	{
		d->genericMapParams.saveToConfigFile(rec, creation);
		d->creationOpts.saveToConfigFile(rec, creation);
		d->insertionOpts.saveToConfigFile(rec, insert);
		d->likelihoodOpts.saveToConfigFile(rec, likelihood);
		return true;
	}
	if (const auto* d = dynamic_cast<const CSubmappedOccupancyGrid3D::TMapDefinition*>(&def))
	{
		d->genericMapParams.saveToConfigFile(rec, creation);
		auto copy = *d;  // the table points into the definition it is built on
		copy.creationFields().write(rec, creation);
		d->insertionOpts.saveToConfigFile(rec, insert);
		d->morphingOpts.saveToConfigFile(rec, insert);
		d->likelihoodOpts.saveToConfigFile(rec, likelihood);
		return true;
	}
	return false;
}

bool isRegisteredMapName(const std::string& name)
{
	for (const auto& [registered, ctors] : mrpt::maps::internal::TMetricMapTypesRegistry::Instance().getAllRegistered())
	{
		std::stringstream ss(registered);
		std::string part;
		while (std::getline(ss, part, ','))
			if (trim(part) == name) return true;
	}
	return false;
}

/** MRPT's TMapGenericParams keys, which every map definition reads and writes without a comment. */
std::string genericMapKeyDescription(const std::string& key)
{
	if (key == "enableSaveAs3DObject") return "include the map in 3D scene exports (MRPT's generic map option)";
	if (key == "enableObservationLikelihood") return "the map takes part in observation likelihoods (MRPT's generic map option)";
	if (key == "enableObservationInsertion") return "observations are inserted into the map (MRPT's generic map option)";
	return "";
}

std::string cell(const std::string& s)
{
	std::string o;
	for (char c : s)
	{
		if (c == '|') o += '\\';
		o += c;
	}
	return o;
}

void appendTable(std::ostringstream& md, const IniSection& s, const std::string& heading)
{
	md << heading << " [" << s.name << "]\n\n";
	md << "| key | default | description |\n|---|---|---|\n";
	for (const auto& k : s.keys)
		md << "| `" << cell(k.key) << "` | " << (k.defaultValue.empty() ? std::string("*(empty)*") : "`" + cell(k.defaultValue) + "`")
		   << " | " << cell(k.description) << " |\n";
	md << "\n";
}
}  // namespace

std::vector<IniSection> slamConfigReference(bool tidyNumbers)
{
	RecordingConfig rec;
	SlamConfig().saveToConfigFile(rec);
	if (tidyNumbers)
		for (auto& s : rec.written)
			for (auto& k : s.keys) k.defaultValue = tidyNumber(k.defaultValue);
	return rec.written;
}

std::vector<std::string> keygridMapPluginNames()
{
	// The registry holds every name of a class ("hocPointsMap", "CHOCPointsMap",
	// "keygrid::CHOCPointsMap"); keep the INI alias of each keygrid class, sorted by name.
	std::vector<std::string> names;
	for (const auto& [name, ctors] : mrpt::maps::internal::TMetricMapTypesRegistry::Instance().getAllRegistered())
	{
		if (name.find("::") != std::string::npos) continue;
		std::unique_ptr<mrpt::maps::TMetricMapInitializer> def(ctors.first());
		if (!def) continue;
		const std::string cls = def->getMetricMapClassType()->className;
		if (cls.rfind("keygrid::", 0) == 0 && cls != "keygrid::" + name) names.push_back(name);
	}
	return names;
}

std::optional<std::vector<IniSection>> mapPluginReference(const std::string& mapName)
{
	if (!isRegisteredMapName(mapName)) return std::nullopt;
	std::unique_ptr<mrpt::maps::TMetricMapInitializer> def(mrpt::maps::TMetricMapInitializer::factory(mapName));
	if (!def) return std::nullopt;
	const std::string prefix = "MappingApplication_" + mapName + "_00";

	// Which keys each section holds, from a load that answers every read with its default.
	RecordingConfig rec;
	rec.existingSections = {prefix, prefix + "_creationOpts", prefix + "_insertOpts", prefix + "_likelihoodOpts"};
	def->loadFromConfigFile(rec, prefix);

	// Defaults and comments as the options write them: keygrid's own types through their
	// options' saveToConfigFile; any other through the text dump (lines `key = value // comment`).
	RecordingConfig saved;
	std::multimap<std::string, IniKey> dumped;
	if (!saveKnownMapDefinition(*def, prefix, saved))
	{
		std::ostringstream dump;
		def->dumpToTextStream(dump);
		std::istringstream lines(dump.str());
		for (std::string line; std::getline(lines, line);)
		{
			const auto eq = line.find('=');
			if (eq == std::string::npos || eq == 0 || line[0] == '[' || line[0] == '-' || line[0] == '=') continue;
			const IniKey k = splitValueAndComment(line.substr(0, eq), line.substr(eq + 1));
			if (!k.key.empty() && k.key.find(' ') == std::string::npos) dumped.emplace(k.key, k);
		}
	}
	auto savedKey = [&](const std::string& section, const std::string& key) -> const IniKey* {
		for (const auto& s : saved.written)
			if (s.name == section)
				for (const auto& k : s.keys)
					if (k.key == key) return &k;
		return nullptr;
	};

	std::vector<IniSection> out;
	for (auto s : rec.read)
	{
		for (auto& k : s.keys)
		{
			if (const IniKey* w = savedKey(s.name, k.key))
			{
				k.defaultValue = w->defaultValue;
				k.description = w->description;
			}
			else if (auto it = dumped.find(k.key); it != dumped.end())
			{
				k.defaultValue = it->second.defaultValue;
				k.description = it->second.description;
				dumped.erase(it);  // a key name used in two sections: take the dump's next one
			}
			if (k.description.empty()) k.description = genericMapKeyDescription(k.key);
			k.defaultValue = tidyNumber(k.defaultValue);
		}
		out.push_back(std::move(s));
	}
	return out;
}

std::string iniReferenceMarkdown()
{
	std::ostringstream md;
	md << "# keygrid INI reference\n\n"
		  "<!-- Generated by `keygrid-slam --ini-reference` (`make ini-reference`) from the options\n"
		  "     structs; do not edit by hand. The test IniReference.MatchesCommittedFile checks it. -->\n\n"
		  "Every key keygrid-slam reads from its INI file, with the default compiled into the options\n"
		  "struct and its description (the comment `saveToConfigFile` writes). A key absent from a file\n"
		  "keeps this default; an invalid value stops the run naming section, key, value and the rule\n"
		  "it breaks: `[tracker] min_inliers = 0 (must be > 0)`.\n\n"
		  "Key names: keygrid-slam's own sections use snake_case (`min_inliers`). The map plugins'\n"
		  "sections, read by MRPT's `CMultiMetricMap`, follow MRPT's own maps: `creationOpts` keys as\n"
		  "`COccupancyGridMap2D`'s (`resolution`, `min_x`, ...), the other keys camelCase as MRPT's\n"
		  "`insertionOpts` (`maxRange`, `logOddsMin`). hocPointsMap predates the rule and keeps snake_case\n"
		  "keys: its `creationOpts` are the `[hoc]` keys.\n\n"
		  "`keygrid-slam --dump-config --config FILE.ini [--set 'section.key=value; ...']` prints the effective configuration of a file.\n"
		  "MRPT's INI reader has no inline comments: put comments on their own lines.\n\n"
		  "## keygrid-slam\n\n";
	for (const auto& s : slamConfigReference()) appendTable(md, s, "###");

	md << "## Map plugins\n\n"
		  "The maps are MRPT `CMetricMap` plugins configured in MRPT's `CMultiMetricMap` format: in\n"
		  "`[MappingApplication]`, `<name>_count = N` creates N maps of a type (keygrid-slam fails naming\n"
		  "the key if `<name>` is not a registered type); the options of the i-th map of a type go in\n"
		  "the sections below with `00` replaced by the two-digit index `i` (00, 01, ...). MRPT's own maps\n"
		  "(`octoMap`, `occupancyGrid`, ...) can be added the same way; see MRPT's documentation for their keys.\n\n";
	for (const auto& name : keygridMapPluginNames())
	{
		const auto sections = mapPluginReference(name);
		if (!sections) continue;  // plugin not built into this libkeygrid_maps
		std::unique_ptr<mrpt::maps::TMetricMapInitializer> def(mrpt::maps::TMetricMapInitializer::factory(name));
		md << "### " << name << " (`" << def->getMetricMapClassType()->className << "`)\n\n"
		   << "Enable with `" << name << "_count = 1` in `[MappingApplication]`.\n\n";
		for (const auto& s : *sections) appendTable(md, s, "####");
	}
	return md.str();
}

}  // namespace keygrid::slam
