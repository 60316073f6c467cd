/** \file SessionStore_read.cpp
 * SessionStore's loaders. Every BLOB is checked against its layout: a row that does not fit
 * throws naming the file, the table and the id.
 */
#include <keygrid/store/KeyFrameImageCodec.h>
#include <keygrid/store/SessionStore.h>

#include <stdexcept>

#include "BlobCodec.h"
#include "SessionStoreImpl.h"

namespace keygrid::store
{
namespace
{
using detail::BlobReader;
using detail::SqliteStatement;

constexpr const char* kKeyFrameColumns =
	"SELECT id, frame_index, stamp, pose, parent, camera, num_levels, level_scale, num_keypoints, keypoints, "
	"undistorted, keypoint_depth, descriptor_type, descriptor_cols, descriptors, landmarks, bow FROM keyframes";

std::string where(const std::string& path, const char* table, std::int64_t id, const char* column)
{
	return "'" + path + "': " + table + " " + std::to_string(static_cast<std::uint64_t>(id)) + " column " + column;
}

BlobReader reader(const SqliteStatement& st, int col, const std::string& path, const char* table, const char* column)
{
	std::size_t n = 0;
	const auto* p = st.blob(col, n);
	return BlobReader(p, n, where(path, table, st.int64(0), column));
}

cv::Mat readMat(const SqliteStatement& st, int col, int rows, int type, int cols, const std::string& path,
				const char* table, const char* column)
{
	auto rd = reader(st, col, path, table, column);
	if (rows == 0 || cols == 0)
	{
		if (!rd.atEnd()) throw std::runtime_error(where(path, table, st.int64(0), column) + ": data for an empty matrix");
		return cv::Mat(rows, cols, type);
	}
	if (type != CV_8U && type != CV_32F)
		throw std::runtime_error(where(path, table, st.int64(0), column) + ": unsupported descriptor type " + std::to_string(type));
	cv::Mat m(rows, cols, type);
	rd.getBytes(m.data, m.total() * m.elemSize());
	if (!rd.atEnd()) throw std::runtime_error(where(path, table, st.int64(0), column) + ": longer than " + std::to_string(rows) + " rows");
	return m;
}

template <class T>
std::vector<T> readExact(BlobReader rd, std::size_t count, const std::string& what)
{
	const std::size_t have = rd.remainingCount(sizeof(T));
	if (have != count)
		throw std::runtime_error(what + ": " + std::to_string(have) + " entries, expected " + std::to_string(count));
	return rd.getArray<T>(count);
}

KeyFrameRecord readKeyFrame(const SqliteStatement& st, const std::string& path, const std::map<std::int64_t, core::RgbdCamera>& cameras)
{
	KeyFrameRecord kf;
	kf.id = static_cast<KeyFrameId>(st.int64(0));
	kf.frameIndex = static_cast<std::uint64_t>(st.int64(1));
	kf.timestamp = st.real(2);
	{
		std::size_t n = 0;
		const auto* p = st.blob(3, n);
		kf.T_world_cam = detail::unpackPose(p, n, where(path, "keyframe", st.int64(0), "pose"));
	}
	kf.hasParent = !st.isNull(4);
	kf.parent = kf.hasParent ? static_cast<KeyFrameId>(st.int64(4)) : 0;
	const auto cam = cameras.find(st.int64(5));
	if (cam == cameras.end())
		throw std::runtime_error(where(path, "keyframe", st.int64(0), "camera") + ": unknown camera " + std::to_string(st.int64(5)));
	kf.camera = cam->second;
	kf.numLevels = static_cast<int>(st.int64(6));
	{
		auto rd = reader(st, 7, path, "keyframe", "level_scale");
		kf.levelScale = rd.getArray<double>(rd.remainingCount(sizeof(double)));
	}
	const auto n = static_cast<std::size_t>(st.int64(8));
	{
		auto rd = reader(st, 9, path, "keyframe", "keypoints");
		if (rd.remainingCount(28) != n)
			throw std::runtime_error(where(path, "keyframe", st.int64(0), "keypoints") + ": not " + std::to_string(n) + " keypoints");
		kf.keypoints.resize(n);
		for (auto& k : kf.keypoints)
		{
			k.pt.x = rd.get<float>();
			k.pt.y = rd.get<float>();
			k.size = rd.get<float>();
			k.angle = rd.get<float>();
			k.response = rd.get<float>();
			k.octave = rd.get<std::int32_t>();
			k.class_id = rd.get<std::int32_t>();
		}
	}
	{
		const auto xy = readExact<float>(reader(st, 10, path, "keyframe", "undistorted"), 2 * n,
										 where(path, "keyframe", st.int64(0), "undistorted"));
		kf.undistorted.resize(n);
		for (std::size_t i = 0; i < n; i++) kf.undistorted[i] = {xy[2 * i], xy[2 * i + 1]};
	}
	kf.keypointDepth =
		readExact<float>(reader(st, 11, path, "keyframe", "keypoint_depth"), n, where(path, "keyframe", st.int64(0), "keypoint_depth"));
	kf.descriptors = readMat(st, 14, static_cast<int>(n), static_cast<int>(st.int64(12)), static_cast<int>(st.int64(13)), path,
							 "keyframe", "descriptors");
	kf.landmarks = readExact<LandmarkId>(reader(st, 15, path, "keyframe", "landmarks"), n,
										 where(path, "keyframe", st.int64(0), "landmarks"));
	{
		auto rd = reader(st, 16, path, "keyframe", "bow");
		const std::size_t m = rd.remainingCount(12);
		kf.bow.resize(m);
		for (auto& e : kf.bow)
		{
			e.word = rd.get<std::uint32_t>();
			e.weight = rd.get<double>();
		}
	}
	return kf;
}

LandmarkRecord readLandmark(const SqliteStatement& st, const std::string& path)
{
	LandmarkRecord lm;
	lm.id = static_cast<LandmarkId>(st.int64(0));
	lm.p_world = {st.real(1), st.real(2), st.real(3)};
	lm.normal = {st.real(4), st.real(5), st.real(6)};
	lm.minDistance = st.real(7);
	lm.maxDistance = st.real(8);
	lm.firstKeyFrame = static_cast<KeyFrameId>(st.int64(9));
	lm.visibleCount = static_cast<int>(st.int64(10));
	lm.foundCount = static_cast<int>(st.int64(11));
	{
		const int type = static_cast<int>(st.int64(12));
		std::size_t bytes = 0;
		st.blob(13, bytes);
		const std::size_t elem = type == CV_32F ? 4 : 1;
		lm.descriptor = bytes == 0 ? cv::Mat() : readMat(st, 13, 1, type, static_cast<int>(bytes / elem), path, "landmark", "descriptor");
	}
	{
		auto rd = reader(st, 14, path, "landmark", "observations");
		const std::size_t m = rd.remainingCount(12);
		for (std::size_t i = 0; i < m; i++)
		{
			const auto kf = rd.get<std::uint64_t>();
			lm.observations[kf] = rd.get<std::int32_t>();
		}
	}
	{
		auto rd = reader(st, 15, path, "landmark", "hoc");
		lm.hocCounts = rd.getArray<std::int16_t>(rd.remainingCount(sizeof(std::int16_t)));
	}
	return lm;
}

}  // namespace

std::vector<KeyFrameRecord> SessionStore::loadKeyFrames() const
{
	auto& im = *m_impl;
	std::vector<KeyFrameRecord> out;
	auto& st = im.statement(std::string(kKeyFrameColumns) + " ORDER BY id");
	while (st.step()) out.push_back(readKeyFrame(st, im.db.path(), im.cameras));
	st.reset();
	return out;
}

std::optional<KeyFrameRecord> SessionStore::loadKeyFrame(KeyFrameId id) const
{
	auto& im = *m_impl;
	auto& st = im.statement(std::string(kKeyFrameColumns) + " WHERE id = ?1");
	st.bind(1, static_cast<std::int64_t>(id));
	std::optional<KeyFrameRecord> out;
	if (st.step()) out = readKeyFrame(st, im.db.path(), im.cameras);
	st.reset();
	return out;
}

EncodedImages SessionStore::loadEncodedImages(KeyFrameId id) const
{
	auto& st = m_impl->statement("SELECT colour_format, colour, depth FROM keyframe_images WHERE keyframe = ?1");
	st.bind(1, static_cast<std::int64_t>(id));
	EncodedImages out;
	if (st.step())
	{
		out.colourFormat = st.text(0);
		out.colour = st.blobVector(1);
		out.depth = st.blobVector(2);
	}
	st.reset();
	return out;
}

KeyFrameImages SessionStore::loadImages(KeyFrameId id) const
{
	const EncodedImages enc = loadEncodedImages(id);
	try
	{
		return KeyFrameImageCodec::decode(enc);
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error("'" + path() + "': images of keyframe " + std::to_string(id) + ": " + e.what());
	}
}

std::vector<LandmarkRecord> SessionStore::loadLandmarks() const
{
	auto& st = m_impl->statement(
		"SELECT id, x, y, z, nx, ny, nz, min_distance, max_distance, first_keyframe, visible_count, found_count, "
		"descriptor_type, descriptor, observations, hoc FROM landmarks ORDER BY id");
	std::vector<LandmarkRecord> out;
	while (st.step()) out.push_back(readLandmark(st, path()));
	st.reset();
	return out;
}

std::vector<CovisibilityEdge> SessionStore::loadCovisibility() const
{
	auto& st = m_impl->statement("SELECT a, b, weight FROM covisibility ORDER BY a, b");
	std::vector<CovisibilityEdge> out;
	while (st.step())
		out.push_back({static_cast<KeyFrameId>(st.int64(0)), static_cast<KeyFrameId>(st.int64(1)), static_cast<int>(st.int64(2))});
	st.reset();
	return out;
}

std::vector<LoopConstraint> SessionStore::loadLoopConstraints() const
{
	auto& st = m_impl->statement(
		"SELECT id, keyframe, loop_keyframe, pose, information, score, inliers FROM loop_constraints ORDER BY id");
	std::vector<LoopConstraint> out;
	while (st.step())
	{
		LoopConstraint l;
		l.keyframe = static_cast<KeyFrameId>(st.int64(1));
		l.loopKeyFrame = static_cast<KeyFrameId>(st.int64(2));
		std::size_t n = 0;
		const auto* p = st.blob(3, n);
		l.T_loop_cur = detail::unpackPose(p, n, where(path(), "loop constraint", st.int64(0), "pose"));
		const auto info = readExact<double>(reader(st, 4, path(), "loop constraint", "information"), 36,
											where(path(), "loop constraint", st.int64(0), "information"));
		for (int r = 0; r < 6; r++)
			for (int c = 0; c < 6; c++) l.information(r, c) = info[static_cast<std::size_t>(6 * r + c)];
		l.score = st.real(5);
		l.inliers = static_cast<int>(st.int64(6));
		out.push_back(l);
	}
	st.reset();
	return out;
}

std::vector<std::string> SessionStore::snapshotNames() const
{
	auto& st = m_impl->statement("SELECT name FROM snapshots ORDER BY name");
	std::vector<std::string> out;
	while (st.step()) out.push_back(st.text(0));
	st.reset();
	return out;
}

std::optional<MapSnapshot> SessionStore::loadSnapshot(const std::string& name) const
{
	auto& st = m_impl->statement("SELECT name, last_keyframe, data FROM snapshots WHERE name = ?1");
	st.bind(1, name);
	std::optional<MapSnapshot> out;
	if (st.step()) out = MapSnapshot{st.text(0), static_cast<KeyFrameId>(st.int64(1)), st.blobVector(2)};
	st.reset();
	return out;
}

SessionCounts SessionStore::counts() const
{
	auto& db = m_impl->db;
	SessionCounts c;
	c.keyframes = static_cast<std::size_t>(db.queryInt("SELECT count(*) FROM keyframes"));
	c.keyframesWithImages = static_cast<std::size_t>(db.queryInt("SELECT count(*) FROM keyframe_images"));
	c.landmarks = static_cast<std::size_t>(db.queryInt("SELECT count(*) FROM landmarks"));
	c.covisibilityEdges = static_cast<std::size_t>(db.queryInt("SELECT count(*) FROM covisibility"));
	c.loopConstraints = static_cast<std::size_t>(db.queryInt("SELECT count(*) FROM loop_constraints"));
	c.snapshots = static_cast<std::size_t>(db.queryInt("SELECT count(*) FROM snapshots"));
	return c;
}

}  // namespace keygrid::store
