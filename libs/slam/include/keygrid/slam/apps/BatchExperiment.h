#pragma once
/** \file BatchExperiment.h
 * The EXPERIMENT.ini of keygrid-batch: a matrix of datasets x configurations (format in
 * doc/user-guide.md, "Batch experiments"), and the per-configuration overrides
 * (`set = section.key=value; ...`) applied to a copy of the configuration file.
 */
#include <optional>
#include <string>
#include <vector>

namespace keygrid::slam
{
/** [batch] */
struct BatchOptions
{
	/** Folder for all outputs (required here or as --output); relative = to the working dir */
	std::string output;
	/** keygrid-slam processes run at the same time (Default: 2) */
	int jobs{2};
	/** Runs of every (dataset, config) pair; the table shows medians (Default: 1) */
	int repeats{1};
	/** Heading of results.md (Default: the experiment file's name) */
	std::string title;
	/** A run still going after this many seconds is stopped and reported failed; 0 = no limit
	 * (Default: 0 s) */
	double timeoutSeconds{0};
};

/** [dataset.NAME]: a recorded sequence, or one keygrid-sim generates first. */
struct DatasetSpec
{
	std::string name;
	/** rawlog or TUM folder (exclusive with scene) */
	std::string input;
	/** ground truth (TUM); empty: INPUT/groundtruth.txt when that exists, else no ATE */
	std::string gt;
	/** keygrid-sim scene INI: the sequence is generated into OUT/_datasets/NAME first */
	std::string scene;
	std::optional<long> seed, frames;  //!< keygrid-sim --seed / --frames
	/** keygrid-sim --set: scene overrides `section.key=value; ...` (e.g. sensor options) */
	std::string simSet;
	/** keygrid-slam --max-frames (Default: 0 = all) */
	long maxFrames{0};

	bool generated() const { return !scene.empty(); }
};

/** One `section.key=value` of a `set =` line. */
struct ConfigOverride
{
	std::string section, key, value;
};

/** [config.NAME]: a keygrid-slam INI file plus overrides. */
struct ConfigSpec
{
	std::string name;
	std::string file;
	std::vector<ConfigOverride> overrides;
};

struct ExperimentSpec
{
	std::string path;  //!< the experiment file ("" for text)
	BatchOptions batch;
	std::vector<DatasetSpec> datasets;  //!< in file order
	std::vector<ConfigSpec> configs;    //!< in file order

	/** Parses and validates an experiment; throws std::invalid_argument naming the file, line,
	 * section and key of the first problem (unknown section or key, bad value, missing key). */
	static ExperimentSpec FromText(const std::string& text, const std::string& origin = "experiment");
	static ExperimentSpec FromFile(const std::string& path);
};

/** Parses `section.key=value; section.key=value` (the section is everything before the key's
 * last dot). Throws std::invalid_argument quoting `where` and the bad item. */
std::vector<ConfigOverride> parseOverrides(const std::string& text, const std::string& where);

/** The INI text with every override applied: an existing key's value is replaced in place
 * (comments and order kept), a missing key is added at the end of its section, a missing
 * section is appended. Section and key names compare case-insensitively, as MRPT's reader. */
std::string applyOverrides(const std::string& iniText, const std::vector<ConfigOverride>& overrides);

/** Throws std::invalid_argument (naming `where` and the key) unless every override names a key
 * that exists in `iniText` or in keygrid-slam's reference (its default configuration, the
 * [MappingApplication] `<map>_count` keys and the option sections of the registered map types):
 * a misspelt key would otherwise be silently ignored. */
void checkOverrideKeys(
	const std::string& iniText, const std::vector<ConfigOverride>& overrides, const std::string& where);

}  // namespace keygrid::slam
