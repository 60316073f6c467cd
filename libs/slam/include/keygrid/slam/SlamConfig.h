#pragma once
/** \file SlamConfig.h
 * Everything one keygrid-slam run is configured with, loaded from one INI file.
 *
 * Sections: [slam] (mode, camera), [features], [tracker], [mapping] (local mapping and local
 * bundle adjustment). Keys absent from the file keep their documented defaults.
 */
#include <keygrid/sfm/FeatureExtractor.h>
#include <keygrid/sfm/LocalMapper.h>
#include <keygrid/sfm/TrackerOptions.h>

#include <string>

namespace keygrid::slam
{
struct SlamConfig
{
	/** "sequential" (deterministic, default for files) or "threaded" (pipelined stages) */
	std::string mode{"sequential"};
	/** Camera for TUM folders: preset name or INI path; empty = guessed from the folder */
	std::string camera;
	sfm::FeatureOptions features;
	sfm::TrackerOptions tracker;
	sfm::LocalMapperOptions mapping;

	void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg);
	void saveToConfigFile(mrpt::config::CConfigFileBase& cfg) const;
	/** Reads an INI file; throws std::invalid_argument naming the file and the bad key. */
	static SlamConfig FromFile(const std::string& path);
};

}  // namespace keygrid::slam
