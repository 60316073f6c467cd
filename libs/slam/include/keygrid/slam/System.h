#pragma once
/** \file System.h
 * The SLAM pipeline for one sequence: feature extraction, tracking and local mapping over a
 * shared sparse map, with the per-frame record from which the final trajectory is built.
 *
 * Sequential mode ([slam] mode = sequential): process(frame) for each frame; tracking, local
 * mapping, map insertion and loop closing run in turn on the calling thread (deterministic).
 *
 * Threaded mode: extract() may run on another thread (it touches no shared state), then
 * processExtracted() in order; it tracks on the calling thread and hands new keyframes to a
 * local-mapping thread, which hands them on to a loop-closing thread (map insertion, loop
 * detection and correction), joined by typed bounded queues. The sparse map is guarded by
 * its mutex: tracking holds it per frame, local mapping releases it while its bundle
 * adjustment is solved, loop closing holds it per keyframe. finish() drains and joins.
 */
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/loop/LoopCloser.h>
#include <keygrid/sfm/LocalMapper.h>
#include <keygrid/sfm/Tracker.h>
#include <keygrid/slam/KeyFrameImageCache.h>
#include <keygrid/slam/MetricMaps.h>
#include <keygrid/slam/SessionLoader.h>
#include <keygrid/slam/SessionRecorder.h>
#include <keygrid/slam/SlamConfig.h>
#include <keygrid/slam/StageTimings.h>

#include <keygrid/core/BoundedQueue.h>

#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace keygrid::slam
{
struct SystemStats
{
	std::size_t frames{0}, tracked{0}, lost{0}, relocalizations{0}, pnpFallbacks{0};
	std::size_t keyframesCreated{0}, keyframesCulled{0}, landmarksCulled{0}, landmarksFused{0};
	/** HOC: landmarks erased by pruning, the bin updates of all frames (hocSeenThrough: the
	 * decrements counted by the seen-through rule), and the frames tracked only with the
	 * fallback selection (sfm::Tracker::track). */
	std::size_t landmarksPrunedHoc{0}, hocIncrements{0}, hocDecrements{0}, hocOccluded{0}, hocRecovered{0};
	std::size_t hocSeenThrough{0}, hocFallbackFrames{0};
	double sumInliers{0}, sumBaKeyFrames{0}, sumBaObservations{0}, sumBaOutliers{0}, sumBaIterations{0};
	/** Threaded mode: local bundle adjustments dropped because a loop closure moved the map
	 * while they were solved. */
	std::size_t baDiscarded{0};
	/** Extend mode: a map started apart from the loaded one merged into it by loop closing. */
	std::size_t mapsMerged{0};
	/** Monocular: frames processed until the map started, the frame that started it included
	 * (0 while it has not started), and the index of that frame. */
	std::size_t framesToInitialize{0};
	std::size_t initializationFrame{0};
};

class System
{
   public:
	/** Session attribute: median share of the local map matched by tracking (see
	 * Tracker::recentShareMedian), the yardstick of relocalizing in the stored map. */
	static constexpr const char* kTrackingShareAttribute = "run.tracking_share_median";
	/** Session attribute: the run's floor frame T_world_floor (maps::poseMatrixText), once
	 * there is one (map outputs of an exported session are written in it). */
	static constexpr const char* kFloorAttribute = "run.T_world_floor";

	/** Starts the mapping and loop-closing threads when cfg.mode is RunMode::Threaded. */
	explicit System(const SlamConfig& cfg);
	/** Stops and joins the threads (what they had queued is still processed). */
	~System();
	System(const System&) = delete;
	System& operator=(const System&) = delete;

	/** Features of a frame (thread-compatible: no shared state touched). */
	sfm::FrameFeatures extract(const core::Frame& frame) const;
	/** Tracks (and, on a new keyframe, maps) a frame whose features are given. */
	const sfm::TrackedFrame& processExtracted(const core::Frame& frame, sfm::FrameFeatures features);
	/** extract + processExtracted. */
	const sfm::TrackedFrame& process(const core::Frame& frame);

	/** Maps fed with every keyframe (optional; see MetricMaps). Monocular with a camera
	 * height: their floor frame is the camera-height estimate's floor, and they follow every
	 * rescale of the map. */
	void attachMaps(std::unique_ptr<MetricMaps> maps)
	{
		m_maps = std::move(maps);
		if (m_maps) m_maps->setImageSource(m_images.get());
		if (m_maps && m_metricScale) m_maps->useFloorFromCameraHeight();
	}
	const MetricMaps* metricMaps() const { return m_maps.get(); }

	/** Records the run into a session file (keygrid-slam --map): each keyframe after its local
	 * mapping and loop closing, the rest in finish(). Before the first frame. */
	void attachRecorder(std::unique_ptr<SessionRecorder> recorder) { m_recorder = std::move(recorder); }
	const SessionRecorder* recorder() const { return m_recorder.get(); }
	/** Loads a stored session's map before the first frame; the first frame relocalizes in it.
	 * `localizeOnly`: no keyframes are added, the map is not refined at the end (finish() only
	 * re-estimates the frames). Otherwise (extend mode; attach the maps first) the stored
	 * keyframes are re-integrated into the metric maps, and when the first [store]
	 * new_map_after_lost_frames frames do not relocalize a new map is started (see
	 * extendState()). The loop closer, when enabled, takes the session's stored
	 * vocabulary if its own is to be trained in the run, and indexes the loaded keyframes for
	 * relocalization. Throws std::logic_error after the first frame. */
	LoadedSession loadSession(const store::SessionStore& session, bool localizeOnly);
	bool localizeOnly() const { return m_localizeOnly; }
	/** Extend mode (a session loaded without localizeOnly): how the run entered the stored
	 * map. `startedNewMap`: the first [store] new_map_after_lost_frames frames did not
	 * relocalize, so a new map was started (merged when SystemStats::mapsMerged > 0);
	 * `waitingForMerge`: its keyframes not in the metric maps (nor the session file) because
	 * it was never merged. */
	struct ExtendState
	{
		bool startedInStoredMap{false}, startedNewMap{false};
		std::size_t waitingForMerge{0};
	};
	ExtendState extendState() const { return {m_startedInStoredMap, m_startedNewMap, m_waitingForMerge.size()}; }

	/** After the last frame: waits for the mapping and loop-closing threads to process every
	 * queued keyframe, then global bundle adjustment and frame re-estimation, as configured in
	 * [refinement]. Idempotent. */
	void finish();

	/** Every processed frame's pose: re-estimated against the final map when finish() did so,
	 * else re-anchored on its reference keyframe's final pose. */
	core::Trajectory trajectory() const;
	/** Poses of the keyframes in the map. */
	core::Trajectory keyframeTrajectory() const;

	/** The map; in threaded mode only after finish() (while the threads run, use
	 * numKeyFrames()). */
	const sfm::SparseMap& map() const { return m_map; }
	/** The keyframes' images (keyframes.simplemap): a keyframe drops its own once it is in the
	 * metric maps and the session file; they are kept in a KeyFrameImageCache
	 * ([store] image_cache_mib) over a spill file in $TMPDIR. */
	const KeyFrameImageCache& keyFrameImages() const { return *m_images; }
	/** Keyframes in the map now (takes the map lock: safe while the threads run). */
	std::size_t numKeyFrames() const;
	const std::vector<sfm::TrackedFrame>& frames() const { return m_frames; }
	/** Monocular: what the frames before the map start did (reference frames, why two-view
	 * initialization failed, the start), at a bounded rate (slam.log); after finish() it ends
	 * with the last message left out, if any. */
	const std::vector<std::string>& initializationLog() const { return m_initLog; }
	/** A snapshot of the counters (several threads update them in threaded mode). */
	SystemStats stats() const;
	/** In threaded mode only after finish(). */
	const std::vector<loop::LoopClosureEvent>& loopClosures() const { return m_loops; }
	/** Report of the final global bundle adjustment (finish()); empty when it did not run. */
	const std::optional<sfm::BundleAdjusterReport>& globalBundleAdjustmentReport() const { return m_globalBa; }
	/** Monocular: the scale the final bundle adjustment gave the map, undone after it
	 * (FinalBundleAdjustment::undoneScale); 1 otherwise */
	double finalScaleUndone() const { return m_finalScaleUndone; }
	/** finish(): how far the final refinement moved the keyframes the maps hold (largest move
	 * of a camera centre or of the point refinement.map_reanchor_depth ahead of it) [m], and
	 * whether the maps were re-anchored for it (more than refinement.map_reanchor_min_shift). */
	struct FinalMapShift
	{
		double largest{0};
		bool reanchored{false};
	};
	const std::optional<FinalMapShift>& finalMapShift() const { return m_finalMapShift; }
	/** Threaded mode: what stopped the mapping or loop-closing thread (empty if nothing did).
	 * processExtracted() throws it; after finish() it is kept here. */
	std::string backgroundError() const;
	const loop::LoopCloser* loopCloser() const { return m_loopCloser.get(); }
	StageTimings& timings() { return m_timings; }
	const StageTimings& timings() const { return m_timings; }
	const SlamConfig& config() const { return m_cfg; }
	/** The map is in metres: measured depth (RGB-D), or a monocular map given metric scale
	 * from camera_height; otherwise its unit is arbitrary (a trajectory is compared with a
	 * Sim(3) alignment). */
	bool metricUnits() const { return m_cfg.sensor == Sensor::Rgbd || (m_metricScale && m_metricScale->metric()); }
	/** Monocular with camera_height: the metric scale keeper; nullptr otherwise. */
	const MetricScale* metricScale() const { return m_metricScale ? &*m_metricScale : nullptr; }

   private:
	/** A new keyframe on its way through local mapping and loop closing. */
	struct KeyFrameJob
	{
		sfm::KeyFrameId keyframe{0};
		std::size_t frameIndex{0};  //!< the frame that created it
		double travelled{0};  //!< camera path length up to that frame [m]
		sfm::PinholeIntrinsics K;
	};
	/** Local mapping of a new keyframe in one go, map lock held (sequential mode). */
	void mapKeyFrame(const KeyFrameJob& job);
	/** Threaded mode: local mapping of a new keyframe, taking the map lock for the phases that
	 * use the map and releasing it while the bundle adjustment is solved. False when the
	 * keyframe was culled while it waited in the queue. */
	bool mapKeyFrameConcurrently(const KeyFrameJob& job);
	/** The counters and timings of one keyframe's local mapping. */
	void recordLocalMapping(const sfm::LocalMappingReport& rep, double seconds);
	/** A tracked frame's counts (tracking outcome, HOC updates, initialization) into m_stats. */
	void countFrame(const sfm::TrackedFrame& tf);
	/** Monocular: a tracker's initialization message into m_initLog, at a bounded rate. */
	void logInitialization(const sfm::TrackedFrame& tf);
	/** Monocular with camera_height, after a new keyframe (map lock held): runs
	 * MetricScale::update and, when it rescaled the map, moves what refers to the map with it:
	 * the tracker, the frames, the maps and `tf` (the frame being tracked; null at the end of
	 * the run). */
	void applyMetricScale(sfm::TrackedFrame* tf);
	/** ... after the whole map was scaled by s about the origin (the path length too). */
	void followWholeMapRescale(double s, sfm::TrackedFrame* tf);
	/** ... after only the newest stretch of path was rescaled (MetricScale::Rescale): the
	 * frames of its keyframes follow them, the maps re-anchor as after a Sim(3) loop. */
	void followWindowRescale(const MetricScale::Rescale& r, sfm::TrackedFrame* tf);
	/** Monocular map start: the frame that became the first keyframe references it now. */
	void attachInitialKeyFrame(const sfm::TrackedFrame& tf);
	/** Map insertion and loop closing of a keyframe, map lock held. `tf`: sequential mode, the
	 * tracker's last frame, which created the keyframe. */
	void insertAndCloseLoops(const KeyFrameJob& job, sfm::TrackedFrame* tf);
	/** Extend mode, the stored map loaded: its keyframes into the metric maps (images from the
	 * session file), and the camera path length it ends with. */
	void reintegrateLoadedKeyFrames(const store::SessionStore& session);
	/** Moves the images of the keyframes of map 0 (in the metric maps and handed to the
	 * recorder) into m_images; a keyframe of a map not merged yet keeps its own until it is. */
	void releaseKeyFrameImages();
	/** Extend mode, until the camera relocalized in the stored map or a new map was started
	 * (map lock held). */
	void startExtending(const sfm::TrackedFrame& tf);
	/** Hands the recorder what a later localization in the session needs from this run. */
	void noteRunAttributes();
	/** finish(): the final bundle adjustment ([refinement]); the keyframes it moved when it
	 * was bounded, nullopt when it moved every one (or did not run). */
	std::optional<std::set<sfm::KeyFrameId>> adjustFinalMap();
	/** finish(): the metric maps re-anchored on the adjusted keyframes (`before`: their poses
	 * before the adjustment) and the landmarks synced; seconds per map stage. Reads the
	 * map only, so it may run beside refineFrames(). */
	std::map<std::string, double> reanchorMaps(const std::map<sfm::KeyFrameId, mrpt::poses::CPose3D>& before);
	/** finish(): every frame re-estimated against the adjusted map (see refineFramePoses). */
	void refineFrames(const std::optional<std::set<sfm::KeyFrameId>>& window);
	/** finish(): the session store's final records; an error is kept as the background error. */
	void storeFinalSession();
	/** A correction of keyframe poses, as every part that holds poses follows it. */
	struct PoseCorrection
	{
		enum class Source
		{
			LoopClosure,  //!< during the run: the tracker and the frame being tracked follow too
			FinalRefinement  //!< in finish(): only the maps (the run is over)
		};
		Source source;
		/** Corrected poses of the keyframes that moved */
		const std::map<sfm::KeyFrameId, mrpt::poses::CPose3D>& newPoses;
		/** LoopClosure: the keyframe that closed the loop (created by the frame being tracked) */
		sfm::KeyFrameId keyframe;
		/** Monocular loop closure (Sim(3)): per keyframe of newPoses, the factor its
		 * camera-frame content grows by (LoopClosureEvent::newScales); null or absent: 1 */
		const std::map<sfm::KeyFrameId, double>* newScales{nullptr};
		/** FinalRefinement of keyframes without depth: their map points as refined
		 * (MetricMaps::refreshedMapPoints); null: the maps keep what they hold */
		const std::map<sfm::KeyFrameId, std::vector<mrpt::math::TPoint3D>>* newPoints{nullptr};
	};
	/** The one place a correction goes out: the map's correction count and the tracker (loop
	 * closures), the frame `tf` that created the keyframe (sequential mode, else null), the
	 * metric maps (re-anchored; told of a loop closure). Frames follow their reference
	 * keyframes by themselves (trajectory()). Returns seconds per map stage. Map lock held. */
	std::map<std::string, double> publishCorrection(const PoseCorrection& c, sfm::TrackedFrame* tf);
	/** Loop detection and correction of a keyframe (map lock held); the event when one closed. */
	std::optional<loop::LoopClosureEvent> closeLoops(const KeyFrameJob& job, sfm::TrackedFrame* tf);
	void mappingThread();
	/** Threaded mode, tracking thread: hands a keyframe to local mapping (throws if a
	 * background thread failed). */
	void queueForMapping(const KeyFrameJob& job);
	/** Threaded mode, tracking thread: blocks until local mapping is at most `lag` keyframes
	 * behind (throws if a background thread failed). */
	void waitForMapping(std::size_t lag);
	void loopClosingThread();
	void setBackgroundError(const std::string& what);
	void throwIfBackgroundFailed() const;
	/** Closes the mapping queue and joins both threads. */
	void joinThreads();

	SlamConfig m_cfg;
	sfm::FeatureExtractor m_extractor;
	sfm::SparseMap m_map;
	sfm::Tracker m_tracker;
	sfm::LocalMapper m_mapper;
	std::vector<sfm::TrackedFrame> m_frames;
	std::vector<std::string> m_initLog;  //!< see initializationLog()
	std::optional<MetricScale> m_metricScale;  //!< see metricScale()
	std::size_t m_initLogLastFrame{0};  //!< frame of the last line of m_initLog
	std::size_t m_initLogSkipped{0};  //!< messages left out since then
	std::string m_initLogLastMessage;  //!< the last of them
	std::vector<std::optional<mrpt::poses::CPose3D>> m_refined;
	std::optional<sfm::PinholeIntrinsics> m_K;
	bool m_finished{false};
	std::unique_ptr<KeyFrameImageCache> m_images;
	std::unique_ptr<MetricMaps> m_maps;
	std::unique_ptr<SessionRecorder> m_recorder;
	bool m_localizeOnly{false};
	// Extend mode (see ExtendState).
	bool m_extending{false}, m_startedInStoredMap{false}, m_startedNewMap{false};
	std::size_t m_lostAtStart{0};
	/** Keyframes of a map not merged yet, for the metric maps once it is. */
	std::vector<KeyFrameJob> m_waitingForMerge;
	std::unique_ptr<loop::LoopCloser> m_loopCloser;
	std::vector<loop::LoopClosureEvent> m_loops;
	std::optional<sfm::BundleAdjusterReport> m_globalBa;
	double m_finalScaleUndone{1.0};  //!< see finalScaleUndone()
	std::optional<FinalMapShift> m_finalMapShift;
	double m_travelled{0};
	std::optional<mrpt::poses::CPose3D> m_lastTrackedPose;
	/** m_map.corrections() when the tracking side last re-based its travelled distance. */
	std::uint64_t m_correctionsSeen{0};
	mutable std::mutex m_statsMutex;  //!< guards m_stats, m_loops, m_backgroundError
	SystemStats m_stats;
	StageTimings m_timings;
	std::string m_backgroundError;
	// Threaded mode.
	/** Keyframes handed to local mapping (tracking thread) and done by it (m_statsMutex);
	 * [slam] mapping_lag bounds the difference. */
	std::size_t m_jobsQueued{0}, m_jobsMapped{0};
	std::condition_variable m_jobMapped;
	std::unique_ptr<core::BoundedQueue<KeyFrameJob>> m_mappingQueue, m_loopQueue;
	std::thread m_mapping, m_loopClosing;
};

}  // namespace keygrid::slam
