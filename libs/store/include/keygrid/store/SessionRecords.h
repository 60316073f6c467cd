#pragma once
/** \file SessionRecords.h
 * The records a session store holds (see SessionStore and doc/session-store.md): plain data in
 * the store's own units, independent of the classes that compute them. SparseMapRecords.h
 * converts between these and the frontend's sfm::KeyFrame / sfm::Landmark.
 */
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/loop/BowVector.h>
#include <keygrid/sfm/Ids.h>
#include <keygrid/sfm/LandmarkState.h>
#include <mrpt/poses/CPose3D.h>
#include <opencv2/core.hpp>

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace keygrid::store
{
using sfm::KeyFrameId;
using sfm::kNoLandmark;
using sfm::LandmarkId;

/** Identity of the vocabulary a session's BoW vectors were computed with: localizing in a
 * session with another vocabulary makes its stored BoW vectors meaningless. */
struct VocabularyIdentity
{
	/** File name (without directory) of the vocabulary, or a name for one trained in-run */
	std::string fileName;
	/** FNV-1a 64-bit hash of the vocabulary's serialized bytes (Vocabulary::save), 16 hex digits */
	std::string hash;
	/** Number of words of the vocabulary */
	std::uint64_t words{0};

	bool empty() const { return hash.empty(); }
	bool operator==(const VocabularyIdentity& o) const
	{
		return fileName == o.fileName && hash == o.hash && words == o.words;
	}
	bool operator!=(const VocabularyIdentity& o) const { return !(*this == o); }
};

/** What a store says about itself (its `meta` table). */
struct SessionMeta
{
	/** Schema version of the file (SessionStore::kSchemaVersion when written by this build) */
	int schemaVersion{0};
	/** keygrid version that created the file, e.g. "0.1.0" */
	std::string keygridVersion;
	/** Creation time, ISO 8601 UTC, e.g. "2026-11-26T14:20:00Z" */
	std::string createdUtc;
	/** Vocabulary of the BoW vectors (empty when the session has none yet) */
	VocabularyIdentity vocabulary;
	/** The session's main camera (each keyframe also names its own, see KeyFrameRecord) */
	core::RgbdCamera camera;
	/** Facts about the mapping run its users want back (e.g. "run.tracking_share_median",
	 * see doc/session-store.md): meta rows whose key starts with "run." */
	std::map<std::string, std::string> attributes;
};

/** A keyframe without its images; images live apart and are loaded on demand
 * (SessionStore::loadImages). Every per-keypoint vector has one entry per keypoint. */
struct KeyFrameRecord
{
	KeyFrameId id{0};
	/** Index of the frame in its input sequence */
	std::uint64_t frameIndex{0};
	/** Timestamp of the frame [s] */
	double timestamp{0};
	/** Pose of the camera (optical frame) in the session's world frame */
	mrpt::poses::CPose3D T_world_cam;
	/** Spanning-tree parent; meaningful when hasParent */
	KeyFrameId parent{0};
	bool hasParent{false};
	/** Intrinsics and depth units of the images */
	core::RgbdCamera camera;
	/** Keypoints as detected (distorted image) [px]; octave = pyramid level */
	std::vector<cv::KeyPoint> keypoints;
	/** Undistorted keypoint positions [px] */
	std::vector<cv::Point2f> undistorted;
	/** Depth at each keypoint [m], 0 where invalid */
	std::vector<float> keypointDepth;
	/** One descriptor per row: CV_8U (binary) or CV_32F */
	cv::Mat descriptors;
	/** Pyramid scale per level (scale^level) and number of levels of the extractor */
	std::vector<double> levelScale;
	int numLevels{8};
	/** Landmark of each keypoint, kNoLandmark where none */
	std::vector<LandmarkId> landmarks;
	/** TF-IDF bag-of-words vector (empty when no vocabulary was available) */
	loop::BowVector bow;
};

/** Compressed images of a keyframe (see KeyFrameImageCodec): encoding is the expensive part
 * and may run on another thread than the one writing the store. */
struct EncodedImages
{
	/** Format of `colour`: "png" (lossless) or "jpg" */
	std::string colourFormat{"png"};
	/** Encoded colour (BGR) or grey image; empty when the keyframe has none */
	std::vector<std::uint8_t> colour;
	/** 16-bit grey PNG of the depth in the camera's depth units (lossless); empty when none */
	std::vector<std::uint8_t> depth;

	bool empty() const { return colour.empty() && depth.empty(); }
};

/** Decoded images of a keyframe. */
struct KeyFrameImages
{
	/** CV_8UC3 (BGR) or CV_8UC1; empty when the keyframe has none */
	cv::Mat colour;
	/** CV_16UC1 in the camera's depth units (metres = value * camera.depthUnits); 0 = invalid */
	cv::Mat depthRaw;
};

/** A landmark as stored: its state as the frontend holds it, and its HOC bin counts. */
struct LandmarkRecord : public sfm::LandmarkState
{
	/** HOC bin counts n_b (empty: never updated) */
	std::vector<std::int16_t> hocCounts;
};

/** Undirected covisibility edge, stored with a < b. weight = shared landmarks; writing an edge
 * with weight <= 0 removes it. */
struct CovisibilityEdge
{
	KeyFrameId a{0}, b{0};
	int weight{0};
};

/** A verified loop closure: the measured pose of the current keyframe in the loop keyframe. */
struct LoopConstraint
{
	/** Keyframe that closed the loop and the older keyframe it was matched with */
	KeyFrameId keyframe{0}, loopKeyFrame{0};
	/** Measured pose of `keyframe` in `loopKeyFrame` */
	mrpt::poses::CPose3D T_loop_cur;
	/** Information of the error (x, y, z, rx, ry, rz) [1/m^2, 1/rad^2], row-major */
	Eigen::Matrix<double, 6, 6> information{Eigen::Matrix<double, 6, 6>::Identity()};
	/** Vocabulary score of the match and RANSAC inliers */
	double score{0};
	int inliers{0};
};

/** New pose of a stored keyframe (local bundle adjustment, loop correction). */
struct KeyFramePose
{
	KeyFrameId id{0};
	mrpt::poses::CPose3D T_world_cam;
};

/** The keypoint -> landmark association of a stored keyframe, when it changed after the
 * keyframe was written (landmarks triangulated later from its keypoints, fused or culled);
 * one entry per keypoint, kNoLandmark where none. */
struct KeyFrameLandmarks
{
	KeyFrameId id{0};
	std::vector<LandmarkId> landmarks;
};

/** A metric map in MRPT's own serialization, gz-compressed: the same bytes MetricMaps writes
 * to its *.bin files (see MapSnapshotCodec). One snapshot per name; a newer one replaces it. */
struct MapSnapshot
{
	/** e.g. "map_2d", "map_3d", "hoc_points" */
	std::string name;
	/** Last keyframe integrated into the map when it was taken */
	KeyFrameId lastKeyFrame{0};
	/** gz-compressed mrpt::serialization archive of one CSerializable (a CMetricMap) */
	std::vector<std::uint8_t> data;
};

/** Everything one SessionStore::write() commits atomically: typically one new keyframe with
 * the landmarks and edges the mapping step created or changed. Applied in the order of the
 * fields: keyframes (+ images), poses, associations, landmarks, erased landmarks, erased
 * keyframes, covisibility, loops, snapshots, attributes. */
struct SessionUpdate
{
	/** New keyframes (an existing id is replaced) and their images, same order; `images` may be
	 * shorter (keyframes without images) */
	std::vector<KeyFrameRecord> keyframes;
	std::vector<EncodedImages> images;
	/** Changed poses of stored keyframes */
	std::vector<KeyFramePose> poses;
	/** Changed keypoint -> landmark associations of stored keyframes */
	std::vector<KeyFrameLandmarks> associations;
	/** New or changed landmarks (upsert by id) */
	std::vector<LandmarkRecord> landmarks;
	/** Removed keyframes (also their images and covisibility edges) and landmarks */
	std::vector<KeyFrameId> erasedKeyFrames;
	std::vector<LandmarkId> erasedLandmarks;
	std::vector<CovisibilityEdge> covisibility;
	std::vector<LoopConstraint> loops;
	std::vector<MapSnapshot> snapshots;
	/** Upserted into SessionMeta::attributes; every key must start with "run." */
	std::map<std::string, std::string> attributes;
};

/** Row counts of a store. */
struct SessionCounts
{
	std::size_t keyframes{0}, keyframesWithImages{0}, landmarks{0}, covisibilityEdges{0},
		loopConstraints{0}, snapshots{0};
};

}  // namespace keygrid::store
