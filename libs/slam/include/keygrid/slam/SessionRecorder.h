#pragma once
/** \file SessionRecorder.h
 * Writes a keygrid-slam run into a session file (keygrid-slam --map FILE, doc/session-store.md)
 * while it maps: after each keyframe's local mapping and loop closing, what changed in the
 * sparse map since the last update goes to the store as one transaction (store::SessionWriter:
 * image compression and the commit run on the writer's thread). A run killed at any moment
 * leaves the file consistent up to the last committed keyframe.
 *
 * What changed is found by comparing the map with what was written: new, moved and erased
 * keyframes; landmarks whose position, observations or descriptor differ; the keypoint ->
 * landmark association of keyframes whose landmarks changed; covisibility edges. Tracking
 * updates the visibility counters and HOC histograms of every landmark in view at every
 * frame: those are written with the landmark's other changes and all of them at the end, so a
 * killed run keeps them as of each landmark's last write.
 * The metric maps are stored as snapshots every `snapshot_every` keyframes and at the end.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/sfm/SparseMap.h>
#include <keygrid/store/SessionWriter.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

namespace keygrid::loop
{
class LoopCloser;
struct LoopClosureEvent;
}  // namespace keygrid::loop

namespace keygrid::slam
{
class MetricMaps;

/** INI section [store]: the session file of keygrid-slam --map / --load-map. */
struct SessionRecorderOptions : public core::FieldTableOptions<SessionRecorderOptions>
{
	/** Store each keyframe's colour and depth images (needed to rebuild the dense maps and for
	 * keyframes.simplemap of an exported session) (Default: true) */
	bool images{true};
	/** RAM for keyframe images that left their keyframes (KeyFrameImageCache: the most
	 * recently used; all of them are in a spill file in $TMPDIR) [MiB], with or without a
	 * session file; 0 = none kept in RAM (Default: 16) */
	int imageCacheMib{16};
	/** Snapshot of the metric maps every this many keyframes, and always at the end; 0 = at
	 * the end only (Default: 25) */
	int snapshotEvery{25};
	/** Extend mode (--load-map without --localize): frames the camera may stay lost at the
	 * start before a new map is begun, apart from the stored one and merged into it by the
	 * first loop closed between the two; 0 = keep relocalizing (Default: 15) */
	int newMapAfterLostFrames{15};
	/** SQLite durability, cache, lock timeout, integrity check on open */
	store::SessionStoreOptions sqlite;
	/** Compression of the keyframe images */
	store::ImageCodecOptions codec;

	/** The [store] keys, SQLite's and the image codec's included. */
	core::OptionFields fields();
	/** Throws std::invalid_argument naming section, key, value and rule of an invalid option. */
	void validate(const std::string& section = "store") const;
};

/** Counters for report.json. */
struct SessionRecorderStats
{
	std::size_t updates{0}, keyframesWritten{0}, landmarksWritten{0}, snapshots{0};
	/** Time spent building the updates on the mapping side [s] */
	double buildSeconds{0};
};

class SessionRecorder
{
   public:
	/** Creates `path` (which must not exist; std::runtime_error naming it otherwise); the
	 * file appears with the first keyframe, whose camera becomes the session's camera. */
	SessionRecorder(const std::string& path, const SessionRecorderOptions& opts);
	/** Continues a stored session (extend mode): `store` open for writing, the map loaded from
	 * it; only what changes from now on is written. Keyframes of a map not merged into the
	 * stored one (KeyFrame::mapId != 0) and their landmarks are written once it is. */
	SessionRecorder(store::SessionStore store, const sfm::SparseMap& loaded, const SessionRecorderOptions& opts);
	~SessionRecorder();

	/** After a keyframe went through local mapping and loop closing (map lock held): writes
	 * what changed. `loop` may be null (no loop closing); `maps` may be null (no metric maps). */
	void afterKeyFrame(const sfm::SparseMap& map, const loop::LoopCloser* loop, const loop::LoopClosureEvent* closed, const MetricMaps* maps);
	/** Whether the next afterKeyFrame() with metric maps stores their snapshots. */
	bool snapshotDueAtNextKeyFrame() const
	{
		return m_opts.snapshotEvery > 0 && m_keyframesSinceSnapshot + 1 >= static_cast<std::size_t>(m_opts.snapshotEvery);
	}
	/** After the final refinement: the last changes and the map snapshots, then waits for the
	 * writer and closes the file. Throws std::runtime_error naming the file on a write error. */
	void finish(const sfm::SparseMap& map, const loop::LoopCloser* loop, const MetricMaps* maps);

	/** Waits until every update so far is committed (throws like finish()). */
	void flush()
	{
		if (m_writer) m_writer->flush();
	}
	/** A fact about the run (a "run." meta key, see store::SessionMeta::attributes), written
	 * with the next update. */
	void setAttribute(const std::string& key, const std::string& value) { m_attributes[key] = value; }

	const std::string& path() const { return m_path; }
	SessionRecorderStats stats() const;
	/** Writer thread totals (image compression and commits). */
	store::SessionWriterStats writerStats() const;

   private:
	/** What was last written of a keyframe: its pose and covisibility. */
	struct WrittenKeyFrame
	{
		mrpt::poses::CPose3D T_world_cam;
		std::map<sfm::KeyFrameId, int> covisibility;
	};
	/** What was last written of a landmark: a hash of its fields and its observers. */
	struct WrittenLandmark
	{
		std::uint64_t hash{0};
		std::vector<sfm::KeyFrameId> observers;
	};

	void open(const sfm::SparseMap& map, const loop::LoopCloser* loop);
	/** The changes since the last update (and records what is written now). withCounters:
	 * also landmarks whose only change is in their visibility counters or HOC histogram. */
	store::SessionWriteJob diff(const sfm::SparseMap& map, const loop::LoopCloser* loop, bool withCounters);
	/** Keyframes of diff(): new ones whole (with images), moved ones as poses, changed
	 * covisibility as edges (weight 0: removed), erased ones by id. */
	void diffKeyFrames(const sfm::SparseMap& map, const loop::LoopCloser* loop, store::SessionWriteJob& job);
	/** A keyframe not written yet: its record (with its BoW vector), images and covisibility. */
	void addNewKeyFrame(sfm::KeyFrameId id, const sfm::KeyFrame& kf, const loop::LoopCloser* loop, store::SessionWriteJob& job);
	/** A keyframe written before: its pose and covisibility changes into `u` and `written`. */
	void diffWrittenKeyFrame(sfm::KeyFrameId id, const sfm::KeyFrame& kf, WrittenKeyFrame& written, store::SessionUpdate& u);
	/** Landmarks of diff(): written when any field changed, erased ones by id. Returns the
	 * keyframes observing them (before and now), whose keypoint -> landmark association is to
	 * be rewritten. */
	std::set<sfm::KeyFrameId> diffLandmarks(const sfm::SparseMap& map, bool withCounters, store::SessionUpdate& u);
	void addSnapshots(store::SessionUpdate& u, const sfm::SparseMap& map, const MetricMaps& maps);

	std::string m_path;
	SessionRecorderOptions m_opts;
	std::unique_ptr<store::SessionWriter> m_writer;
	std::unordered_map<sfm::KeyFrameId, WrittenKeyFrame> m_keyframes;
	std::unordered_map<sfm::LandmarkId, WrittenLandmark> m_landmarks;
	std::map<std::string, std::string> m_attributes;  //!< for the next update
	std::size_t m_loopsWritten{0};
	std::size_t m_keyframesSinceSnapshot{0};
	bool m_vocabularyNoted{false};
	bool m_finished{false};
	SessionRecorderStats m_stats;
};

/** Hash of what a landmark record holds (position, normal, distances, observations,
 * descriptor; withCounters: also the visible / found counters and the HOC counts). */
std::uint64_t landmarkHash(const sfm::Landmark& lm, bool withCounters);

}  // namespace keygrid::slam
