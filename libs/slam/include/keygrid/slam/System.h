#pragma once
/** \file System.h
 * The SLAM pipeline for one sequence: feature extraction, tracking and local mapping over a
 * shared sparse map, with the per-frame record from which the final trajectory is built.
 *
 * Sequential use: process(frame) for each frame (deterministic). Pipelined use: extract()
 * may run on another thread (it touches no shared state), then processExtracted() in order.
 */
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/sfm/LocalMapper.h>
#include <keygrid/sfm/Tracker.h>
#include <keygrid/slam/LoopCloser.h>
#include <keygrid/slam/MetricMaps.h>
#include <keygrid/slam/SlamConfig.h>
#include <keygrid/slam/StageTimings.h>

#include <memory>
#include <optional>
#include <vector>

namespace keygrid::slam
{
struct SystemStats
{
	std::size_t frames{0}, tracked{0}, lost{0}, relocalizations{0}, pnpFallbacks{0};
	std::size_t keyframesCreated{0}, keyframesCulled{0}, landmarksCulled{0}, landmarksFused{0};
	/** HOC: landmarks erased by pruning, and the bin updates of all frames. */
	std::size_t landmarksPrunedHoc{0}, hocIncrements{0}, hocDecrements{0}, hocOccluded{0}, hocRecovered{0};
	double sumInliers{0}, sumBaKeyFrames{0}, sumBaObservations{0}, sumBaOutliers{0};
};

class System
{
   public:
	explicit System(const SlamConfig& cfg);

	/** Features of a frame (thread-compatible: no shared state touched). */
	sfm::FrameFeatures extract(const core::Frame& frame) const;
	/** Tracks (and, on a new keyframe, maps) a frame whose features are given. */
	const sfm::TrackedFrame& processExtracted(const core::Frame& frame, sfm::FrameFeatures features);
	/** extract + processExtracted. */
	const sfm::TrackedFrame& process(const core::Frame& frame);

	/** Maps fed with every keyframe (optional; see MetricMaps). */
	void attachMaps(std::unique_ptr<MetricMaps> maps) { m_maps = std::move(maps); }
	const MetricMaps* metricMaps() const { return m_maps.get(); }

	/** After the last frame: global bundle adjustment and frame re-estimation, as configured
	 * in [refinement]. Idempotent. */
	void finish();

	/** Every processed frame's pose: re-estimated against the final map when finish() did so,
	 * else re-anchored on its reference keyframe's final pose. */
	core::Trajectory trajectory() const;
	/** Poses of the keyframes in the map. */
	core::Trajectory keyframeTrajectory() const;

	const sfm::SparseMap& map() const { return m_map; }
	const std::vector<sfm::TrackedFrame>& frames() const { return m_frames; }
	const SystemStats& stats() const { return m_stats; }
	const std::vector<LoopClosureEvent>& loopClosures() const { return m_loops; }
	const LoopCloser* loopCloser() const { return m_loopCloser.get(); }
	StageTimings& timings() { return m_timings; }
	const StageTimings& timings() const { return m_timings; }
	const SlamConfig& config() const { return m_cfg; }

   private:
	SlamConfig m_cfg;
	sfm::FeatureExtractor m_extractor;
	sfm::SparseMap m_map;
	sfm::Tracker m_tracker;
	sfm::LocalMapper m_mapper;
	std::vector<sfm::TrackedFrame> m_frames;
	std::vector<std::optional<mrpt::poses::CPose3D>> m_refined;
	std::optional<sfm::PinholeIntrinsics> m_K;
	bool m_finished{false};
	std::unique_ptr<MetricMaps> m_maps;
	std::unique_ptr<LoopCloser> m_loopCloser;
	std::vector<LoopClosureEvent> m_loops;
	double m_travelled{0};
	std::optional<mrpt::poses::CPose3D> m_lastTrackedPose;
	SystemStats m_stats;
	StageTimings m_timings;
};

}  // namespace keygrid::slam
