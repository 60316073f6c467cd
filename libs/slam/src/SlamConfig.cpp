#include <keygrid/core/ConfigReading.h>
#include <keygrid/slam/IniReference.h>
#include <keygrid/slam/SlamConfig.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/system/filesystem.h>

#include <algorithm>
#include <stdexcept>

namespace keygrid::slam
{
const char* toString(RunMode m) { return m == RunMode::Threaded ? "threaded" : "sequential"; }

const char* toString(Sensor s) { return s == Sensor::Monocular ? "monocular" : "rgbd"; }

RunMode runModeFromString(const std::string& text, const std::string& what)
{
	if (text == "sequential") return RunMode::Sequential;
	if (text == "threaded") return RunMode::Threaded;
	throw std::invalid_argument(what + " '" + text + "' (expected sequential or threaded)");
}

core::OptionFields RefinementOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("global_bundle_adjustment", globalBundleAdjustment, "bundle-adjust everything after the last frame");
	f.add("global_iterations", globalIterations, "upper bound on its iterations (it stops on convergence)", R::atLeast(1));
	f.add("global_max_keyframes", globalMaxKeyFrames, "keyframes it moves at most: around the loops and the newest (0 = all)", R::atLeast(0));
	f.add("refine_frames", refineFrames, "re-estimate every frame that is not a keyframe against the final map");
	f.add("frame_pose_rounds", framePoseRounds, "outlier-classification rounds of each frame's re-estimation", R::atLeast(1));
	f.add("map_reanchor_min_shift", mapReanchorMinShift, "re-anchor the maps only if a keyframe moved more than this [m]", R::atLeast(0));
	f.add("map_reanchor_depth", mapReanchorDepth, "...measured also at this depth ahead of the camera [m]", R::atLeast(0));
	return f;
}

void RefinementOptions::validate(const std::string& s) const { core::validateFields(*this, s); }

core::OptionFields SlamConfig::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.addCustom(
		"mode",
		{[this](const std::string& text) {
			 if (text != toString(RunMode::Sequential) && text != toString(RunMode::Threaded))
				 throw std::invalid_argument("expected sequential or threaded");
			 mode = runModeFromString(text, "[slam] mode =");
		 },
		 [this] { return std::string(toString(mode)); }},
		"sequential | threaded", R::oneOf({"sequential", "threaded"}));
	f.addCustom(
		"sensor",
		{[this](const std::string& text) {
			 if (text != toString(Sensor::Rgbd) && text != toString(Sensor::Monocular)) throw std::invalid_argument("expected rgbd or monocular");
			 sensor = text == toString(Sensor::Monocular) ? Sensor::Monocular : Sensor::Rgbd;
		 },
		 [this] { return std::string(toString(sensor)); }},
		"rgbd | monocular (images only: two-view map start, arbitrary scale)", R::oneOf({"rgbd", "monocular"}));
	f.addCustom(
		"camera", {[this](const std::string& text) { camera = text; }, [this] { return camera.empty() ? std::string("auto") : camera; }},
		"preset (fr1 fr2 fr3 icl kinect), INI file, or auto");
	f.add("mapping_lag", mappingLag, "threaded: keyframes local mapping may lag behind tracking (0: none)", R::inRange(0, 5));
	f.add("busy_keyframe_ratio", busyKeyFrameRatio, "threaded, lag > 0: no keyframe while mapping is busy unless tracking < this x reference (0: off)", R::inRange(0, 1));
	f.add("wait_for_weak_keyframes", waitForWeakKeyFrames, "threaded, lag > 0: after a keyframe inserted while mapping was busy, wait until mapping is done");
	f.add("playback_rate", playbackRate, "recorded inputs: release frames at their timestamps' pace x this, as a camera (1: as recorded; 0: as fast as processed)", R::inRange(0, 1000));
	return f;
}

namespace
{
/** The options struct of every section after [slam], with its section name. */
template <class Config, class Visit>
void forEachSection(Config& cfg, Visit&& visit)
{
	visit(cfg.features, "features");
	visit(cfg.tracker, "tracker");
	visit(cfg.tracker.hoc, "hoc");
	visit(cfg.tracker.mono, "monocular");
	visit(cfg.mapping, "mapping");
	visit(cfg.refinement, "refinement");
	visit(cfg.maps, "maps");
	visit(cfg.floor, "floor");
	visit(cfg.loop, "loop_closing");
	visit(cfg.store, "store");
	visit(cfg.metricScale, "camera_height_scale");
}
}  // namespace

double SlamConfig::deferralRatio() const
{
	if (mode != RunMode::Threaded || mappingLag == 0) return 0.0;
	return sensor == Sensor::Monocular ? tracker.mono.busyKeyFrameRatio : busyKeyFrameRatio;
}

bool SlamConfig::waitsForWeakKeyFrames() const
{
	if (deferralRatio() == 0) return false;
	return sensor == Sensor::Monocular ? tracker.mono.waitForWeakKeyFrames : waitForWeakKeyFrames;
}

void SlamConfig::loadFromConfigFile(const mrpt::config::CConfigFileBase& c)
{
	fields().read(c, "slam");
	core::validateFields(*this, "slam");
	forEachSection(*this, [&c](auto& options, const char* section) { options.loadFromConfigFile(c, section); });
	// The depth residual model is shared by tracking and bundle adjustment.
	mapping.ba.bf = tracker.pose.bf;
	mapping.ba.disparitySigma = tracker.pose.disparitySigma;
	tracker.monocular = sensor == Sensor::Monocular;
	loop.monocular = sensor == Sensor::Monocular;
	// The two-view map is bundle-adjusted as local mapping adjusts its windows.
	tracker.mono.ba = mapping.ba;
}

void SlamConfig::saveToConfigFile(mrpt::config::CConfigFileBase& c) const
{
	core::writeFields(*this, c, "slam");
	forEachSection(*this, [&c](const auto& options, const char* section) { options.saveToConfigFile(c, section); });
}

namespace
{
/** A value must be of its default's kind (MRPT's readers turn "forty" into 0, "1000abc" into
 * 1000, "1e3" for an integer into 1 and "maybe" into false): a boolean default takes
 * true/false/1/0, an integer default (written without a decimal point) a whole number, a
 * floating-point one a finite number; text is its reader's to check. */
void checkValueLikeDefault(const mrpt::config::CConfigFileBase& c, const std::string& section, const IniKey& ref)
{
	const std::string& d = ref.defaultValue;
	double number = 0;
	if (d == "true" || d == "false")
		core::readBoolean(c, section, ref.key, false);
	else if (!d.empty() && d.find_first_not_of("-0123456789") == std::string::npos)
		core::readWholeNumber(c, section, ref.key, 0);
	else if (core::parseTrimmedDouble(d, number))
		core::readFiniteNumber(c, section, ref.key, 0.0);
}
}  // namespace

void SlamConfig::checkKnownKeys(const mrpt::config::CConfigFileBase& c)
{
	// Every section is one SlamConfig owns, a map plugin's (MetricMaps checks those) or the
	// live camera's: a misspelt section would otherwise be ignored with all its keys.
	const auto reference = slamConfigReference(false);
	std::vector<std::string> sections;
	c.getAllSections(sections);
	for (const auto& name : sections)
	{
		const auto startsWith = [&](const std::string& p) { return name.compare(0, p.size(), p) == 0; };
		const bool ours = std::any_of(reference.begin(), reference.end(), [&](const IniSection& r) { return r.name == name; });
		if (ours || name.empty() || name == "MappingApplication" || startsWith("MappingApplication_") || name == "live" || startsWith("live_")) continue;
		std::string known;
		for (const auto& r : reference) known += (known.empty() ? "" : ", ") + r.name;
		throw std::invalid_argument(
			"[" + name + "]: unknown section (keygrid-slam reads " + known +
			", the map plugins' MappingApplication*, the live camera's live*)");
	}
	// The sections SlamConfig owns, with the keys its saveToConfigFile writes. (Map sections
	// belong to the plugins; MetricMaps checks those by type.)
	for (const auto& sec : reference)
	{
		if (!c.sectionExists(sec.name)) continue;
		std::vector<std::string> keys;
		c.getAllKeys(sec.name, keys);
		for (const auto& k : keys)
		{
			const auto ref = std::find_if(sec.keys.begin(), sec.keys.end(), [&](const IniKey& r) { return r.key == k; });
			if (ref == sec.keys.end())
				throw std::invalid_argument(
					"[" + sec.name + "] " + k + ": unknown key (typo? `keygrid-slam --dump-config` lists every key)");
			checkValueLikeDefault(c, sec.name, *ref);
		}
	}
}

SlamConfig SlamConfig::FromFile(const std::string& path)
{
	if (!mrpt::system::fileExists(path)) throw std::invalid_argument("config file '" + path + "' does not exist");
	return FromConfig(mrpt::config::CConfigFile(path), path);
}

SlamConfig SlamConfig::FromConfig(const mrpt::config::CConfigFileBase& cfg, const std::string& origin)
{
	SlamConfig c;
	try
	{
		c.loadFromConfigFile(cfg);
		checkKnownKeys(cfg);
	}
	catch (const std::exception& e)
	{
		throw std::invalid_argument(origin + ": " + e.what());
	}
	return c;
}

}  // namespace keygrid::slam
