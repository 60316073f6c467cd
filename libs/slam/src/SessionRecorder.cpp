#include <keygrid/core/ConfigReading.h>
#include <keygrid/loop/LoopCloser.h>
#include <keygrid/slam/MetricMaps.h>
#include <keygrid/slam/SessionRecorder.h>
#include <keygrid/store/MapSnapshotCodec.h>
#include <keygrid/store/SparseMapRecords.h>
#include <keygrid/store/VocabularyFingerprint.h>
#include <mrpt/config/CConfigFileBase.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <set>
#include <stdexcept>

namespace keygrid::slam
{
namespace
{
/** A 64-bit hash of raw bytes, eight at a time (change detection, not security). */
struct Hasher
{
	std::uint64_t h{0x9E3779B97F4A7C15ull};
	void word(std::uint64_t w)
	{
		h ^= w + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
		h *= 0xBF58476D1CE4E5B9ull;
		h ^= h >> 31;
	}
	void add(const void* p, std::size_t n)
	{
		const auto* b = static_cast<const unsigned char*>(p);
		std::size_t i = 0;
		for (; i + 8 <= n; i += 8)
		{
			std::uint64_t w;
			std::memcpy(&w, b + i, 8);
			word(w);
		}
		std::uint64_t tail = 0;
		std::memcpy(&tail, b + i, n - i);
		word(tail ^ (static_cast<std::uint64_t>(n) << 56));
	}
	template <typename T>
	void add(const T& v)
	{
		add(&v, sizeof v);
	}
};

bool samePose(const mrpt::poses::CPose3D& a, const mrpt::poses::CPose3D& b)
{
	return a.m_coords == b.m_coords && a.getRotationMatrix() == b.getRotationMatrix();
}

/** Names of the metric-map snapshots: the names of MetricMaps' *.bin files. */
std::string snapshotName(const mrpt::maps::CMetricMap& m, std::map<std::string, int>& seen)
{
	const std::string cls = m.GetRuntimeClass()->className;
	const std::string bare = cls.substr(cls.rfind(':') == std::string::npos ? 0 : cls.rfind(':') + 1);
	std::string base = bare == "CISMOccupancyGrid2D" ? "map_2d" : bare == "CSubmappedOccupancyGrid3D" ? "map_3d" : bare == "CHOCPointsMap" ? "hoc_points" : bare;
	const int n = seen[base]++;
	return n == 0 ? base : base + "_" + std::to_string(n);
}
}  // namespace

std::uint64_t landmarkHash(const sfm::Landmark& lm, bool withCounters)
{
	Hasher f;
	f.add(lm.p_world.data(), 3 * sizeof(double));
	f.add(lm.normal.data(), 3 * sizeof(double));
	f.add(lm.minDistance);
	f.add(lm.maxDistance);
	f.word(lm.firstKeyFrame);
	for (const auto& [kf, kp] : lm.observations) f.word((static_cast<std::uint64_t>(kf) << 20) ^ static_cast<std::uint64_t>(kp));
	if (!lm.descriptor.empty() && lm.descriptor.isContinuous()) f.add(lm.descriptor.data, lm.descriptor.total() * lm.descriptor.elemSize());
	if (withCounters)
	{
		f.word((static_cast<std::uint64_t>(static_cast<std::uint32_t>(lm.visibleCount)) << 32) | static_cast<std::uint32_t>(lm.foundCount));
		const auto& hoc = lm.hoc.counts();
		if (!hoc.empty()) f.add(hoc.data(), hoc.size() * sizeof(hoc[0]));
	}
	return f.h;
}

core::OptionFields SessionRecorderOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("images", images, "store each keyframe's colour and depth images");
	f.add("snapshot_every", snapshotEvery, "metric-map snapshots every N keyframes (0: at the end only)", R::atLeast(0));
	f.add("image_cache_mib", imageCacheMib, "RAM for keyframe images out of their keyframes [MiB] (the rest in a spill file)", R::inRange(0, 1 << 20));
	f.add("new_map_after_lost_frames", newMapAfterLostFrames, "extend mode: lost frames at the start before a new map begins (0: never)", R::atLeast(0));
	f.append(sqlite.fields());
	f.append(codec.fields());
	return f;
}

void SessionRecorderOptions::validate(const std::string& s) const { core::validateFields(*this, s); }

SessionRecorder::SessionRecorder(const std::string& path, const SessionRecorderOptions& opts) : m_path(path), m_opts(opts)
{
	opts.validate("store");
	if (std::filesystem::exists(path))
		throw std::runtime_error("session file '" + path + "' exists already (--map creates a new session; --load-map continues one)");
	const auto dir = std::filesystem::path(path).parent_path();
	if (!dir.empty() && !std::filesystem::is_directory(dir))
		throw std::runtime_error("session file '" + path + "': folder '" + dir.string() + "' does not exist");
}

SessionRecorder::SessionRecorder(store::SessionStore s, const sfm::SparseMap& loaded, const SessionRecorderOptions& opts)
	: m_path(s.path()), m_opts(opts)
{
	for (const auto& [id, kf] : loaded.keyframes()) m_keyframes[id] = {kf.T_world_cam, kf.covisibility};
	for (const auto& [id, lm] : loaded.landmarks())
	{
		WrittenLandmark w{landmarkHash(lm, false), {}};
		for (const auto& [kf, kp] : lm.observations) w.observers.push_back(kf);
		m_landmarks[id] = std::move(w);
	}
	m_loopsWritten = s.counts().loopConstraints;
	m_vocabularyNoted = !s.meta().vocabulary.empty();
	store::SessionWriterOptions wo;
	wo.images = opts.codec;
	m_writer = std::make_unique<store::SessionWriter>(std::move(s), wo);
}

SessionRecorder::~SessionRecorder() = default;

void SessionRecorder::open(const sfm::SparseMap& map, const loop::LoopCloser* loop)
{
	if (m_writer) return;
	store::SessionMeta meta;
	if (!map.keyframes().empty()) meta.camera = map.keyframes().begin()->second.features.camera;
	if (loop && loop->hasVocabulary() && !loop->vocabularyFile().empty())
	{
		meta.vocabulary = store::vocabularyIdentityOfFile(loop->vocabularyFile());
		m_vocabularyNoted = true;
	}
	store::SessionWriterOptions wo;
	wo.images = m_opts.codec;
	m_writer = std::make_unique<store::SessionWriter>(store::SessionStore::Create(m_path, meta, m_opts.sqlite), wo);
}

store::SessionWriteJob SessionRecorder::diff(const sfm::SparseMap& map, const loop::LoopCloser* loop, bool withCounters)
{
	store::SessionWriteJob job;
	auto& u = job.update;
	diffKeyFrames(map, loop, job);
	const std::set<sfm::KeyFrameId> dirtyAssociations = diffLandmarks(map, withCounters, u);
	u.attributes.swap(m_attributes);
	m_attributes.clear();
	// New keyframes carry their association in their record; erased ones have none.
	std::set<sfm::KeyFrameId> fresh;
	for (const auto& r : u.keyframes) fresh.insert(r.id);
	for (const auto kf : dirtyAssociations)
		if (!fresh.count(kf) && m_keyframes.count(kf) && map.hasKeyFrame(kf)) u.associations.push_back({kf, map.keyframe(kf).landmarks});
	return job;
}

void SessionRecorder::diffKeyFrames(const sfm::SparseMap& map, const loop::LoopCloser* loop, store::SessionWriteJob& job)
{
	auto& u = job.update;
	for (const auto& [id, kf] : map.keyframes())
	{
		if (kf.mapId != 0) continue;  // a map not merged yet has no place in the file's frame
		auto it = m_keyframes.find(id);
		if (it == m_keyframes.end())
			addNewKeyFrame(id, kf, loop, job);
		else
			diffWrittenKeyFrame(id, kf, it->second, u);
	}
	for (auto it = m_keyframes.begin(); it != m_keyframes.end();)
	{
		if (map.hasKeyFrame(it->first))
		{
			++it;
			continue;
		}
		u.erasedKeyFrames.push_back(it->first);
		it = m_keyframes.erase(it);
	}
}

void SessionRecorder::addNewKeyFrame(sfm::KeyFrameId id, const sfm::KeyFrame& kf, const loop::LoopCloser* loop, store::SessionWriteJob& job)
{
	const loop::BowVector* bow = loop ? loop->bowOf(id) : nullptr;
	job.update.keyframes.push_back(store::toRecord(kf, bow ? *bow : loop::BowVector{}));
	store::KeyFrameImageSource img;
	if (m_opts.images)
	{
		img.colour = kf.colour;
		img.depth = kf.depth;
		img.depthUnits = kf.features.camera.depthUnits;
	}
	job.images.push_back(img);
	for (const auto& e : store::covisibilityOf(kf)) job.update.covisibility.push_back(e);
	m_keyframes[id] = {kf.T_world_cam, kf.covisibility};
	m_stats.keyframesWritten++;
}

void SessionRecorder::diffWrittenKeyFrame(sfm::KeyFrameId id, const sfm::KeyFrame& kf, WrittenKeyFrame& written, store::SessionUpdate& u)
{
	if (!samePose(written.T_world_cam, kf.T_world_cam))
	{
		u.poses.push_back({id, kf.T_world_cam});
		written.T_world_cam = kf.T_world_cam;
	}
	if (written.covisibility == kf.covisibility) return;
	for (const auto& [other, w] : kf.covisibility)
	{
		const auto old = written.covisibility.find(other);
		if (old == written.covisibility.end() || old->second != w) u.covisibility.push_back({std::min(id, other), std::max(id, other), w});
	}
	for (const auto& [other, w] : written.covisibility)
		if (!kf.covisibility.count(other)) u.covisibility.push_back({std::min(id, other), std::max(id, other), 0});
	written.covisibility = kf.covisibility;
}

std::set<sfm::KeyFrameId> SessionRecorder::diffLandmarks(const sfm::SparseMap& map, bool withCounters, store::SessionUpdate& u)
{
	std::set<sfm::KeyFrameId> dirtyAssociations;
	for (const auto& [id, lm] : map.landmarks())
	{
		if (!lm.observations.empty() && map.keyframe(lm.observations.begin()->first).mapId != 0) continue;
		const std::uint64_t h = landmarkHash(lm, withCounters);
		auto it = m_landmarks.find(id);
		if (it != m_landmarks.end() && it->second.hash == h) continue;
		if (it == m_landmarks.end()) it = m_landmarks.emplace(id, WrittenLandmark{}).first;
		for (const auto kf : it->second.observers) dirtyAssociations.insert(kf);
		it->second.hash = h;
		it->second.observers.clear();
		for (const auto& [kf, kp] : lm.observations)
		{
			it->second.observers.push_back(kf);
			dirtyAssociations.insert(kf);
		}
		u.landmarks.push_back(store::toRecord(lm));
	}
	for (auto it = m_landmarks.begin(); it != m_landmarks.end();)
	{
		if (map.hasLandmark(it->first))
		{
			++it;
			continue;
		}
		for (const auto kf : it->second.observers) dirtyAssociations.insert(kf);
		u.erasedLandmarks.push_back(it->first);
		it = m_landmarks.erase(it);
	}
	m_stats.landmarksWritten += u.landmarks.size();
	return dirtyAssociations;
}

void SessionRecorder::addSnapshots(store::SessionUpdate& u, const sfm::SparseMap& map, const MetricMaps& maps)
{
	const store::KeyFrameId last = map.keyframes().empty() ? 0 : map.keyframes().rbegin()->first;
	std::map<std::string, int> seen;
	for (const auto& m : maps.maps().maps) u.snapshots.push_back(store::MapSnapshotCodec::encode(snapshotName(*m, seen), *m, last));
	m_stats.snapshots++;
	m_keyframesSinceSnapshot = 0;
}

void SessionRecorder::afterKeyFrame(const sfm::SparseMap& map, const loop::LoopCloser* loop, const loop::LoopClosureEvent* closed, const MetricMaps* maps)
{
	const auto t0 = std::chrono::steady_clock::now();
	open(map, loop);
	auto job = diff(map, loop, false);
	if (closed)
	{
		store::LoopConstraint c;
		c.keyframe = closed->keyframe;
		c.loopKeyFrame = closed->loopKeyFrame;
		c.T_loop_cur = closed->T_loop_cur;
		c.score = closed->score;
		c.inliers = closed->inliers;
		job.update.loops.push_back(c);
		m_loopsWritten++;
	}
	m_keyframesSinceSnapshot++;
	if (maps && m_opts.snapshotEvery > 0 && m_keyframesSinceSnapshot >= static_cast<std::size_t>(m_opts.snapshotEvery))
		addSnapshots(job.update, map, *maps);
	m_stats.updates++;
	m_stats.buildSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	m_writer->submit(std::move(job));
}

void SessionRecorder::finish(const sfm::SparseMap& map, const loop::LoopCloser* loop, const MetricMaps* maps)
{
	if (m_finished) return;
	m_finished = true;
	if (map.keyframes().empty() && !m_writer) return;  // nothing was mapped: no file
	open(map, loop);
	auto job = diff(map, loop, true);
	if (maps) addSnapshots(job.update, map, *maps);
	m_writer->submit(std::move(job));
	m_writer->close();
	// A vocabulary trained in the run exists nowhere else: it goes into the file.
	if (loop && loop->hasVocabulary() && !m_vocabularyNoted)
	{
		auto s = store::SessionStore::Open(m_path, store::SessionStore::Mode::ReadWrite, [&] {
			auto o = m_opts.sqlite;
			o.integrityCheck = "none";
			return o;
		}());
		s.storeVocabulary(loop->vocabulary(), "trained in the run");
	}
}

SessionRecorderStats SessionRecorder::stats() const { return m_stats; }

store::SessionWriterStats SessionRecorder::writerStats() const
{
	return m_writer ? m_writer->stats() : store::SessionWriterStats{};
}

}  // namespace keygrid::slam
