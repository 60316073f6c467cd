#pragma once
/** \file SlamConfig.h
 * Everything one keygrid-slam run is configured with, loaded from one INI file.
 *
 * Sections: [slam] (mode, sensor, camera), [features], [tracker], [monocular] (map start and
 * keyframes without depth), [camera_height_scale] (monocular: metric scale from the camera's
 * height), [mapping] (local mapping and local
 * bundle adjustment), [refinement] (final global bundle adjustment and frame re-estimation),
 * [loop_closing] (place recognition and pose graph), [maps] (how keyframes feed the maps), [floor]
 * (the floor frame every map output is written in), [store] (the session file of --map) and [MappingApplication] (the maps themselves, MRPT's
 * CMultiMetricMap format, see MetricMaps). Keys absent from the file keep their documented defaults.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/loop/LoopCloser.h>
#include <keygrid/sfm/FeatureExtractor.h>
#include <keygrid/sfm/LocalMapper.h>
#include <keygrid/sfm/TrackerOptions.h>
#include <keygrid/slam/MetricMaps.h>
#include <keygrid/slam/MetricScale.h>
#include <keygrid/slam/SessionRecorder.h>

#include <string>

namespace keygrid::slam
{
/** Batch refinement after the last frame (file inputs). */
struct RefinementOptions : public core::FieldTableOptions<RefinementOptions>
{
	/** Bundle-adjust all keyframes and landmarks at the end (Default: true) */
	bool globalBundleAdjustment{true};
	/** Upper bound on the Levenberg-Marquardt iterations of the final global bundle adjustment,
	 * which otherwise stops when an iteration lowers the cost by less than 1e-6. A safety
	 * bound, set above what a long loop needs to converge: stopping earlier leaves part of
	 * the loop correction undone (iteration counts in doc/evaluation.md) (Default: 100) */
	int globalIterations{100};
	/** Bound of the final bundle adjustment's cost: in a map with more keyframes than this,
	 * it moves only this many, grown through the covisibility graph from both ends of every
	 * closed loop and from the newest keyframe (sfm::growBundleWindow); the keyframes outside
	 * that also see their landmarks hold them in place, and only the frames whose reference
	 * keyframe moved are re-estimated. The rest of the map keeps what local bundle
	 * adjustments and the loops' pose graphs made of it, which is less accurate on a long loop
	 * than one adjustment of every keyframe (doc/evaluation.md). 0: every keyframe and frame, at
	 * a cost that grows faster than the map (Default: 0) */
	int globalMaxKeyFrames{0};
	/** Re-estimate the frames' poses against the refined map: every frame after a global
	 * bundle adjustment of every keyframe, the frames whose reference keyframe it moved after a
	 * bounded one (Default: true) */
	bool refineFrames{true};
	/** Outlier-classification rounds of each frame's re-estimation ([tracker] pose rounds has
	 * the tracker's). Each frame starts from its tracked pose with the observations tracking
	 * kept as inliers, so the classification rounds a rough start needs have little left to do
	 * (doc/evaluation.md, "Final step") (Default: 2) */
	int framePoseRounds{2};
	/** The maps are re-anchored on the refined keyframe poses only when the refinement moved a
	 * keyframe's camera centre, or the point map_reanchor_depth ahead of it, by more than this;
	 * a rebuild of the 2D grid and a morph of the 3D grid cost as much as the whole map.
	 * 0: whenever a keyframe moved at all (Default: 0 m) */
	double mapReanchorMinShift{0.0};
	/** Depth of that point [m]: about the range the maps are filled to (Default: 4 m) */
	double mapReanchorDepth{4.0};

	/** The [refinement] keys. */
	core::OptionFields fields();
	/** Throws std::invalid_argument naming section, key, value and rule of an invalid option. */
	void validate(const std::string& section = "refinement") const;
};

/** How the stages of a run share the machine. */
enum class RunMode
{
	Sequential,  //!< one stage after the other: deterministic, the default for files
	Threaded  //!< tracking, local mapping and loop closing on their own threads (pipelined)
};
/** "sequential" or "threaded": [slam] mode, keygrid-slam --mode, report.json "mode". */
const char* toString(RunMode m);
/** The inverse of toString(RunMode); throws std::invalid_argument
 * "<what> '<text>' (expected sequential or threaded)" for any other text. */
RunMode runModeFromString(const std::string& text, const std::string& what);

/** The camera a run reads: RGB-D (images and depth) or monocular (images only, the depth of
 * an RGB-D input ignored). */
enum class Sensor
{
	Rgbd,
	Monocular
};
/** "rgbd" or "monocular": [slam] sensor, report.json "sensor". */
const char* toString(Sensor s);

struct SlamConfig
{
	/** Sequential (deterministic, default for files) or threaded (pipelined stages)
	 * (Default: sequential) */
	RunMode mode{RunMode::Sequential};
	/** rgbd: images and depth; monocular: images only (rawlogs of CObservationImage, TUM
	 * folders' rgb.txt, the images of RGB-D inputs), the map starts from two views and its
	 * scale is arbitrary ([monocular] section, doc/frontend.md "Monocular mode")
	 * (Default: rgbd) */
	Sensor sensor{Sensor::Rgbd};
	/** Camera for TUM folders: preset name or INI path; "auto" (or empty) = camera.ini in the
	 * folder, else guessed from the folder name (Default: auto) */
	std::string camera{"auto"};
	/** Threaded mode: how many keyframes local mapping may still be working on while tracking
	 * goes on. 0: tracking waits until each new keyframe is mapped (triangulated, fused,
	 * bundle-adjusted) before the next frame, so it sees the map sequential mode sees (the
	 * same trajectory byte for byte without loop closures); tracking and local mapping then
	 * take turns. 1: local mapping works on a keyframe while tracking goes on, and
	 * busy_keyframe_ratio keeps tracking from queueing more keyframes meanwhile: a higher
	 * frame rate than 0 at about the same accuracy (doc/frontend.md "Modes"). At most 5 (the
	 * queue holds 4 waiting keyframes). (Default: 1) */
	int mappingLag{1};
	/** Threaded mode with mapping_lag > 0: while local mapping is still working on a keyframe,
	 * tracking inserts a new one only at the keyframe timeout or when it tracks fewer than this
	 * share of the reference keyframe's landmarks (ORB-SLAM2's rule, which uses 0.25); the
	 * frames in between are tracked against the map being refined. Lower: fewer keyframes,
	 * faster and less accurate; higher: the reverse (doc/frontend.md "Modes"). 0 = insert
	 * whenever tracking asks, busy or not. Monocular mode takes [monocular] busy_keyframe_ratio
	 * instead. (Default: 0.35) */
	double busyKeyFrameRatio{0.35};
	/** Threaded mode with mapping_lag > 0: after a keyframe that tracking inserted while local
	 * mapping was still busy (it fell below busy_keyframe_ratio), tracking waits until local
	 * mapping has done every queued keyframe, as with mapping_lag 0, before the next frame:
	 * in a fast turn the next frames then track against that keyframe's new landmarks
	 * instead of running ahead of them. Monocular mode takes [monocular]
	 * wait_for_weak_keyframes instead. (Default: false) */
	bool waitForWeakKeyFrames{false};
	/** Recorded inputs: > 0 releases the frames at the pace of their timestamps times this
	 * factor, as a camera delivers them (1: the recording's own rate; a gap counts for at most
	 * 1 s), so that a threaded run has the time budget of a live camera; none is dropped.
	 * 0: as fast as the pipeline takes them. The trajectory of a sequential run does not
	 * depend on it. (Default: 0) */
	double playbackRate{0.0};
	/** Whether tracking waits after a keyframe inserted while local mapping was busy:
	 * wait_for_weak_keyframes, in monocular mode [monocular] wait_for_weak_keyframes; false
	 * when no keyframe is deferred (deferralRatio() 0). */
	bool waitsForWeakKeyFrames() const;
	/** The share that defers keyframes in threaded mode: busy_keyframe_ratio, in monocular
	 * mode [monocular] busy_keyframe_ratio; 0 when no keyframe is deferred (sequential mode,
	 * mapping_lag 0). */
	double deferralRatio() const;
	sfm::FeatureOptions features;
	sfm::TrackerOptions tracker;
	sfm::LocalMapperOptions mapping;
	RefinementOptions refinement;
	MapFeedOptions maps;
	maps::FloorFrameOptions floor;
	loop::LoopClosingOptions loop;
	SessionRecorderOptions store;
	/** Monocular: metric scale from camera_height ([camera_height_scale]; 0 = none). */
	MetricScaleOptions metricScale;

	/** The [slam] keys (mode, sensor, camera, mapping_lag, busy_keyframe_ratio,
	 * wait_for_weak_keyframes, playback_rate). */
	core::OptionFields fields();
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg);
	void saveToConfigFile(mrpt::config::CConfigFileBase& cfg) const;
	/** Throws std::invalid_argument naming the first key of a SlamConfig section ([slam],
	 * [tracker], [hoc], ...) that no option reads. */
	static void checkKnownKeys(const mrpt::config::CConfigFileBase& cfg);
	/** Loads, validates and checks for unknown keys; errors start with `origin` (the file). */
	static SlamConfig FromConfig(const mrpt::config::CConfigFileBase& cfg, const std::string& origin);
	/** FromConfig() of an INI file; throws std::invalid_argument when it does not exist. */
	static SlamConfig FromFile(const std::string& path);
};

}  // namespace keygrid::slam
