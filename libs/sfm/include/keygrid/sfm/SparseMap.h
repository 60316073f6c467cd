#pragma once
/** \file SparseMap.h
 * Keyframes and landmarks of the SfM frontend, and the covisibility graph between keyframes.
 * A plain container: the algorithms that change it (Tracker, LocalMapper, bundle adjustment)
 * live in their own classes. Ids are monotonic, containers ordered, so iteration (and every
 * result built from it) is deterministic.
 */
#include <keygrid/maps/HocHistogram.h>
#include <keygrid/sfm/FrameFeatures.h>
#include <keygrid/sfm/Ids.h>
#include <keygrid/sfm/LandmarkState.h>
#include <mrpt/poses/CPose3D.h>

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <mutex>
#include <utility>
#include <vector>

namespace keygrid::sfm
{
struct Landmark : public LandmarkState
{
	/** Histogram of Oriented Cameras (used when [hoc] enabled; see HocFrontend.h). */
	maps::HocHistogram hoc;

	double foundRatio() const { return static_cast<double>(foundCount) / std::max(1, visibleCount); }
};

struct KeyFrame
{
	KeyFrameId id{0};
	std::size_t frameIndex{0};
	double timestamp{0};
	mrpt::poses::CPose3D T_world_cam;
	FrameFeatures features;
	/** Landmark of each keypoint, kNoLandmark if none. */
	std::vector<LandmarkId> landmarks;
	/** Depth image [m] (kept for the dense maps; shares the frame's buffer). */
	cv::Mat depth;
	/** Image of the keyframe for the exported observations: the frame's colour image (BGR,
	 * CV_8UC3) or, when the source has none, its grey image (a copy). */
	cv::Mat colour;
	/** Covisibility: other keyframe -> number of shared landmarks (>= threshold). */
	std::map<KeyFrameId, int> covisibility;
	/** Keyframe that was the reference when this one was created (spanning tree parent). */
	KeyFrameId parent{0};
	bool hasParent{false};
	/** Which map the keyframe belongs to: 0, the map anchored in the world frame; a map
	 * started where the loaded one had no place to relocalize (extend mode) gets a new id and
	 * its own provisional frame until a loop merges it into map 0 (LoopCloser). Keyframes of
	 * different maps share no landmarks. */
	std::uint32_t mapId{0};

	Eigen::Vector3d cameraCenter() const;
	int trackedLandmarks(int minObservations = 1, const class SparseMap* map = nullptr) const;
};

class SparseMap
{
   public:
	/** Adds a keyframe (its id is assigned here) and returns it. */
	KeyFrame& addKeyFrame(KeyFrame kf);
	/** Puts back a keyframe with its own id (a map loaded from a session store); later
	 * addKeyFrame() ids follow the largest one. Throws std::invalid_argument when the id is
	 * taken. Covisibility and landmarks are the caller's (restoreLandmark, updateCovisibility). */
	KeyFrame& restoreKeyFrame(KeyFrame kf);
	/** Puts back a landmark with its own id and observations; each observing keyframe must be in
	 * the map already (its keypoint is pointed at the landmark). Throws std::invalid_argument
	 * when the id is taken or an observation names a missing keyframe or keypoint. */
	void restoreLandmark(Landmark lm);
	/** Creates a landmark observed by keypoint kp of keyframe kf. */
	LandmarkId addLandmark(const Eigen::Vector3d& p_world, KeyFrameId kf, int kp);
	void addObservation(LandmarkId lm, KeyFrameId kf, int kp);
	void eraseObservation(LandmarkId lm, KeyFrameId kf);
	void eraseLandmark(LandmarkId lm);
	/** Removes a keyframe and its observations; landmarks left with < 1 observation go too.
	 * Its pose relative to its parent is remembered (see poseOf) so that frames referencing it
	 * still get a pose that follows later map refinements. */
	void eraseKeyFrame(KeyFrameId kf);
	/** Pose of a keyframe, also of an erased one (through its parent chain); false if unknown. */
	bool poseOf(KeyFrameId kf, mrpt::poses::CPose3D& T_world_kf) const;
	/** Keeps `keep`, moves the observations of `gone` to it (duplicate fusion). */
	void replaceLandmark(LandmarkId gone, LandmarkId keep);
	/** The landmark that now stands for `id`: `id` itself, or the one it was fused into
	 * (following later fusions too); kNoLandmark if that one was erased. Frames keep the ids
	 * they matched; this maps them onto the current map. */
	LandmarkId resolve(LandmarkId id) const;
	/** resolve() and findLandmark() of every id issued so far, as a table indexed by id:
	 * entry i is the landmark that now stands for landmark i, nullptr when there is none. One
	 * pass over the map, for callers that resolve many ids (a lookup each costs more); valid
	 * until the map changes. */
	std::vector<const Landmark*> resolvedLandmarks() const;

	/** Scales the map by s > 0 about the world origin (monocular maps, whose unit is
	 * arbitrary): keyframe camera centres, landmark positions and their scale-invariance
	 * distances, and the relative poses kept for erased keyframes; orientations unchanged.
	 * Throws std::invalid_argument unless s is finite and > 0. */
	void rescale(double s);
	/** Recomputes normal, distance limits and representative descriptor of a landmark. */
	void updateLandmarkStats(LandmarkId lm);
	/** Recomputes the covisibility edges of kf (and the reverse edges). */
	void updateCovisibility(KeyFrameId kf, int minShared = 15);
	/** Up to n covisible keyframes by decreasing weight. */
	std::vector<KeyFrameId> bestCovisibles(KeyFrameId kf, std::size_t n) const;

	bool hasKeyFrame(KeyFrameId id) const { return m_keyframes.count(id) > 0; }
	bool hasLandmark(LandmarkId id) const { return m_landmarks.count(id) > 0; }
	KeyFrame& keyframe(KeyFrameId id) { return m_keyframes.at(id); }
	const KeyFrame& keyframe(KeyFrameId id) const { return m_keyframes.at(id); }
	Landmark& landmark(LandmarkId id) { return m_landmarks.at(id); }
	/** The landmark, or nullptr when it does not exist (one lookup instead of has + get). */
	const Landmark* findLandmark(LandmarkId id) const
	{
		const auto it = m_landmarks.find(id);
		return it == m_landmarks.end() ? nullptr : &it->second;
	}
	Landmark* findLandmark(LandmarkId id) { return const_cast<Landmark*>(std::as_const(*this).findLandmark(id)); }
	const Landmark& landmark(LandmarkId id) const { return m_landmarks.at(id); }
	const std::map<KeyFrameId, KeyFrame>& keyframes() const { return m_keyframes; }
	const std::map<LandmarkId, Landmark>& landmarks() const { return m_landmarks; }
	std::size_t numKeyFrames() const { return m_keyframes.size(); }
	std::size_t numLandmarks() const { return m_landmarks.size(); }

	/** The one lock of map updates, for threaded mode (tracking, mapping and loop closing on
	 * separate threads; see slam::System): whoever reads or writes the map while the others
	 * run holds it. LocalMappingPass::solve() is the local mapping step that runs without it. */
	std::mutex& mutex() const { return m_mutex; }
	/** Counts corrections that moved the whole map (loop closures). A result computed from an
	 * older state, e.g. a bundle adjustment solved without the lock, must not be written back
	 * across one. */
	std::uint64_t corrections() const { return m_corrections; }
	void noteCorrection() { ++m_corrections; }

   private:
	std::map<KeyFrameId, KeyFrame> m_keyframes;
	std::map<LandmarkId, Landmark> m_landmarks;
	/** erased keyframe -> (parent, T_parent_kf) */
	std::map<KeyFrameId, std::pair<KeyFrameId, mrpt::poses::CPose3D>> m_erased;
	/** fused landmark -> the landmark that absorbed it (replaceLandmark) */
	std::map<LandmarkId, LandmarkId> m_replacedBy;
	KeyFrameId m_nextKf{0};
	LandmarkId m_nextLm{0};
	std::uint64_t m_corrections{0};
	mutable std::mutex m_mutex;
};

/** Cosine of the largest angle between the ray from the landmark's first observing keyframe
 * (still in the map) and the ray from each other one (1: seen from one place only): how well
 * its position is triangulated without depth. */
double largestParallaxCos(const SparseMap& map, const Landmark& lm);

/** Eigen position of a CPose3D translation. */
inline Eigen::Vector3d translationOf(const mrpt::poses::CPose3D& p) { return {p.x(), p.y(), p.z()}; }
/** The pose's translation multiplied by s, its rotation kept (a map scaled about its origin). */
inline void scaleTranslation(mrpt::poses::CPose3D& p, double s)
{
	p.x(s * p.x());
	p.y(s * p.y());
	p.z(s * p.z());
}

}  // namespace keygrid::sfm
