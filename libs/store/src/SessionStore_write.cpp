/** \file SessionStore_write.cpp
 * SessionStore::write(): one transaction per SessionUpdate, prepared statements reused.
 */
#include <keygrid/store/SessionStore.h>

#include <algorithm>
#include <stdexcept>

#include "BlobCodec.h"
#include "SessionStoreImpl.h"

namespace keygrid::store
{
namespace
{
using detail::BlobWriter;

std::int64_t sqlId(std::uint64_t id) { return static_cast<std::int64_t>(id); }

void validateKeyFrame(const KeyFrameRecord& kf)
{
	const std::size_t n = kf.keypoints.size();
	const auto fail = [&](const std::string& field, std::size_t got) {
		throw std::invalid_argument("SessionStore::write: keyframe " + std::to_string(kf.id) + ": " + field + " has " +
									std::to_string(got) + " entries for " + std::to_string(n) + " keypoints");
	};
	if (kf.undistorted.size() != n) fail("undistorted", kf.undistorted.size());
	if (kf.keypointDepth.size() != n) fail("keypointDepth", kf.keypointDepth.size());
	if (kf.landmarks.size() != n) fail("landmarks", kf.landmarks.size());
	if (static_cast<std::size_t>(kf.descriptors.rows) != n) fail("descriptors (rows)", static_cast<std::size_t>(kf.descriptors.rows));
	if (!kf.descriptors.empty() && kf.descriptors.channels() != 1)
		throw std::invalid_argument("SessionStore::write: keyframe " + std::to_string(kf.id) +
									": descriptors must have one channel, got " + std::to_string(kf.descriptors.channels()));
}

/** Rows of a descriptor matrix, contiguous. */
std::vector<std::uint8_t> packMat(const cv::Mat& m)
{
	if (m.empty()) return {};
	const cv::Mat c = m.isContinuous() ? m : m.clone();
	const auto* p = c.ptr<std::uint8_t>();
	return std::vector<std::uint8_t>(p, p + c.total() * c.elemSize());
}

std::vector<std::uint8_t> packKeypoints(const std::vector<cv::KeyPoint>& kps)
{
	BlobWriter w(kps.size() * 28);
	for (const auto& k : kps)
	{
		w.put<float>(k.pt.x);
		w.put<float>(k.pt.y);
		w.put<float>(k.size);
		w.put<float>(k.angle);
		w.put<float>(k.response);
		w.put<std::int32_t>(k.octave);
		w.put<std::int32_t>(k.class_id);
	}
	return std::move(w.bytes());
}

std::vector<std::uint8_t> packPoints(const std::vector<cv::Point2f>& pts)
{
	BlobWriter w(pts.size() * 8);
	for (const auto& p : pts)
	{
		w.put<float>(p.x);
		w.put<float>(p.y);
	}
	return std::move(w.bytes());
}

std::vector<std::uint8_t> packBow(const loop::BowVector& bow)
{
	BlobWriter w(bow.size() * 12);
	for (const auto& e : bow)
	{
		w.put<std::uint32_t>(e.word);
		w.put<double>(e.weight);
	}
	return std::move(w.bytes());
}

std::vector<std::uint8_t> packObservations(const std::map<KeyFrameId, int>& obs)
{
	BlobWriter w(obs.size() * 12);
	for (const auto& [kf, kp] : obs)
	{
		w.put<std::uint64_t>(kf);
		w.put<std::int32_t>(kp);
	}
	return std::move(w.bytes());
}

template <class T>
std::vector<std::uint8_t> packArray(const std::vector<T>& v)
{
	BlobWriter w;
	w.putArray(v);
	return std::move(w.bytes());
}

}  // namespace

void SessionStore::write(const SessionUpdate& u)
{
	auto& im = *m_impl;
	if (im.mode != Mode::ReadWrite) throw std::logic_error("SessionStore::write: '" + path() + "' was opened read-only");
	for (const auto& kf : u.keyframes) validateKeyFrame(kf);
	if (u.images.size() > u.keyframes.size())
		throw std::invalid_argument("SessionStore::write: " + std::to_string(u.images.size()) + " image sets for " +
									std::to_string(u.keyframes.size()) + " keyframes");
	for (const auto& e : u.covisibility)
		if (e.a == e.b)
			throw std::invalid_argument("SessionStore::write: covisibility edge from keyframe " + std::to_string(e.a) + " to itself");
	for (const auto& s : u.snapshots)
		if (s.name.empty()) throw std::invalid_argument("SessionStore::write: a map snapshot without a name");

	try
	{
		detail::SqliteTransaction tx(im.db);
		for (std::size_t i = 0; i < u.keyframes.size(); i++)
		{
			const auto& kf = u.keyframes[i];
			const std::int64_t cam = im.cameraId(kf.camera);
			const auto pose = detail::packPose(kf.T_world_cam);
			const auto levels = packArray(kf.levelScale);
			const auto kps = packKeypoints(kf.keypoints);
			const auto und = packPoints(kf.undistorted);
			const auto depth = packArray(kf.keypointDepth);
			const auto desc = packMat(kf.descriptors);
			const auto lms = packArray(kf.landmarks);
			const auto bow = packBow(kf.bow);
			auto& st = im.statement(
				"INSERT OR REPLACE INTO keyframes(id, frame_index, stamp, pose, parent, camera, num_levels, level_scale, "
				"num_keypoints, keypoints, undistorted, keypoint_depth, descriptor_type, descriptor_cols, descriptors, "
				"landmarks, bow) VALUES(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17)");
			st.bind(1, sqlId(kf.id)).bind(2, sqlId(kf.frameIndex)).bind(3, kf.timestamp).bindBlob(4, pose);
			if (kf.hasParent) st.bind(5, sqlId(kf.parent));
			else st.bindNull(5);
			st.bind(6, cam).bind(7, std::int64_t(kf.numLevels)).bindBlob(8, levels);
			st.bind(9, std::int64_t(kf.keypoints.size())).bindBlob(10, kps).bindBlob(11, und).bindBlob(12, depth);
			st.bind(13, std::int64_t(kf.descriptors.empty() ? CV_8U : kf.descriptors.type()))
				.bind(14, std::int64_t(kf.descriptors.cols))
				.bindBlob(15, desc)
				.bindBlob(16, lms)
				.bindBlob(17, bow);
			st.run();
			if (i < u.images.size() && !u.images[i].empty())
			{
				const auto& img = u.images[i];
				auto& si = im.statement(
					"INSERT OR REPLACE INTO keyframe_images(keyframe, colour_format, colour, depth) VALUES(?1, ?2, ?3, ?4)");
				si.bind(1, sqlId(kf.id)).bind(2, img.colourFormat).bindBlob(3, img.colour).bindBlob(4, img.depth);
				si.run();
			}
		}
		for (const auto& p : u.poses)
		{
			const auto pose = detail::packPose(p.T_world_cam);
			auto& st = im.statement("UPDATE keyframes SET pose = ?1 WHERE id = ?2");
			st.bindBlob(1, pose).bind(2, sqlId(p.id));
			st.run();
			if (sqlite3_changes(im.db.handle()) != 1)
				throw std::invalid_argument("SessionStore::write: new pose for keyframe " + std::to_string(p.id) +
											", which '" + path() + "' does not hold");
		}
		for (const auto& a : u.associations)
		{
			const auto lms = packArray(a.landmarks);
			auto& st = im.statement("UPDATE keyframes SET landmarks = ?1 WHERE id = ?2 AND num_keypoints = ?3");
			st.bindBlob(1, lms).bind(2, sqlId(a.id)).bind(3, std::int64_t(a.landmarks.size()));
			st.run();
			if (sqlite3_changes(im.db.handle()) != 1)
				throw std::invalid_argument("SessionStore::write: landmarks of keyframe " + std::to_string(a.id) + " (" +
											std::to_string(a.landmarks.size()) + " keypoints), which '" + path() +
											"' does not hold with that many keypoints");
		}
		for (const auto& lm : u.landmarks)
		{
			const auto desc = packMat(lm.descriptor);
			const auto obs = packObservations(lm.observations);
			const auto hoc = packArray(lm.hocCounts);
			auto& st = im.statement(
				"INSERT INTO landmarks(id, x, y, z, nx, ny, nz, min_distance, max_distance, first_keyframe, visible_count, "
				"found_count, descriptor_type, descriptor, observations, hoc) "
				"VALUES(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16) "
				"ON CONFLICT(id) DO UPDATE SET x = excluded.x, y = excluded.y, z = excluded.z, nx = excluded.nx, "
				"ny = excluded.ny, nz = excluded.nz, min_distance = excluded.min_distance, "
				"max_distance = excluded.max_distance, first_keyframe = excluded.first_keyframe, "
				"visible_count = excluded.visible_count, found_count = excluded.found_count, "
				"descriptor_type = excluded.descriptor_type, descriptor = excluded.descriptor, "
				"observations = excluded.observations, hoc = excluded.hoc");
			st.bind(1, sqlId(lm.id)).bind(2, lm.p_world.x()).bind(3, lm.p_world.y()).bind(4, lm.p_world.z());
			st.bind(5, lm.normal.x()).bind(6, lm.normal.y()).bind(7, lm.normal.z());
			st.bind(8, lm.minDistance).bind(9, lm.maxDistance).bind(10, sqlId(lm.firstKeyFrame));
			st.bind(11, std::int64_t(lm.visibleCount)).bind(12, std::int64_t(lm.foundCount));
			st.bind(13, std::int64_t(lm.descriptor.empty() ? CV_8U : lm.descriptor.type()));
			st.bindBlob(14, desc).bindBlob(15, obs).bindBlob(16, hoc);
			st.run();
		}
		for (const LandmarkId id : u.erasedLandmarks)
		{
			auto& st = im.statement("DELETE FROM landmarks WHERE id = ?1");
			st.bind(1, sqlId(id));
			st.run();
		}
		for (const KeyFrameId id : u.erasedKeyFrames)
		{
			for (const char* sql : {"DELETE FROM keyframes WHERE id = ?1", "DELETE FROM keyframe_images WHERE keyframe = ?1",
									"DELETE FROM covisibility WHERE a = ?1", "DELETE FROM covisibility WHERE b = ?1"})
			{
				auto& st = im.statement(sql);
				st.bind(1, sqlId(id));
				st.run();
			}
		}
		for (const auto& e : u.covisibility)
		{
			const std::int64_t a = sqlId(std::min(e.a, e.b)), b = sqlId(std::max(e.a, e.b));
			auto& st = e.weight > 0 ? im.statement(
										  "INSERT INTO covisibility(a, b, weight) VALUES(?1, ?2, ?3) "
										  "ON CONFLICT(a, b) DO UPDATE SET weight = excluded.weight")
									: im.statement("DELETE FROM covisibility WHERE a = ?1 AND b = ?2");
			st.bind(1, a).bind(2, b);
			if (e.weight > 0) st.bind(3, std::int64_t(e.weight));
			st.run();
		}
		for (const auto& l : u.loops)
		{
			const auto pose = detail::packPose(l.T_loop_cur);
			BlobWriter info(36 * sizeof(double));
			for (int r = 0; r < 6; r++)
				for (int c = 0; c < 6; c++) info.put<double>(l.information(r, c));
			auto& st = im.statement(
				"INSERT INTO loop_constraints(keyframe, loop_keyframe, pose, information, score, inliers) "
				"VALUES(?1, ?2, ?3, ?4, ?5, ?6)");
			st.bind(1, sqlId(l.keyframe)).bind(2, sqlId(l.loopKeyFrame)).bindBlob(3, pose).bindBlob(4, info.bytes());
			st.bind(5, l.score).bind(6, std::int64_t(l.inliers));
			st.run();
		}
		for (const auto& s : u.snapshots)
		{
			auto& st = im.statement(
				"INSERT OR REPLACE INTO snapshots(name, last_keyframe, written_utc, format, data) "
				"VALUES(?1, ?2, strftime('%Y-%m-%dT%H:%M:%SZ', 'now'), 'mrpt-serialization-gz', ?3)");
			st.bind(1, s.name).bind(2, sqlId(s.lastKeyFrame)).bindBlob(3, s.data);
			st.run();
		}
		for (const auto& [key, value] : u.attributes)
		{
			if (key.rfind("run.", 0) != 0 || key.size() == 4)
				throw std::invalid_argument("SessionStore::write: attribute '" + key + "' (names start with 'run.')");
			auto& st = im.statement("INSERT INTO meta(key, value) VALUES(?1, ?2) ON CONFLICT(key) DO UPDATE SET value = excluded.value");
			st.bind(1, key).bind(2, value);
			st.run();
		}
		tx.commit();
		for (const auto& [key, value] : u.attributes) im.meta.attributes[key] = value;
	}
	catch (...)
	{
		// Cameras inserted by the rolled-back transaction are gone from the file too.
		im.loadCameras();
		throw;
	}
}

}  // namespace keygrid::store
