#pragma once
/** \file LocalMapper.h
 * Refines the map around each new keyframe: covisibility, culling of weak new landmarks,
 * fusion of duplicated landmarks with the neighbours, local bundle adjustment, and culling of
 * redundant keyframes.
 */
#include <keygrid/sfm/LocalBundleAdjuster.h>
#include <keygrid/sfm/Matcher.h>
#include <keygrid/sfm/SparseMap.h>

#include <deque>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace mrpt::config
{
class CConfigFileBase;
}

namespace keygrid::sfm
{
struct LocalMapperOptions
{
	/** Neighbour keyframes searched for duplicates of the new keyframe's landmarks (Default: 10) */
	int fuseNeighbours{10};
	/** Search radius for fusion [px at level 0] (Default: 3) */
	float fuseRadius{3.f};
	/** Largest descriptor distance for fusion, ORB bits (Default: 50) */
	float fuseMaxDistanceOrb{50.f};
	/** A new landmark is culled if matched in less than this share of the frames it was
	 * predicted in (Default: 0.25) */
	double minFoundRatio{0.25};
	/** A keyframe is culled when this share of its landmarks is seen by >= 3 other keyframes
	 * at the same or a finer scale (Default: 0.9) */
	double redundantKeyFrameRatio{0.9};
	/** Keyframes searched for new landmarks by triangulation of keypoints without one (Default: 5) */
	int triangulationNeighbours{5};
	/** Smallest parallax for a triangulated landmark [deg] (Default: 1.0) */
	double minParallaxDeg{1.0};
	/** Run local bundle adjustment (Default: true) */
	bool localBundleAdjustment{true};
	BundleAdjusterOptions ba;

	void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section);
	void saveToConfigFile(mrpt::config::CConfigFileBase& cfg, const std::string& section) const;
};

struct LocalMappingReport
{
	int culledLandmarks{0}, fusedLandmarks{0}, addedObservations{0}, culledKeyFrames{0}, triangulated{0};
	BundleAdjusterReport ba;
	/** Threaded mode: the bundle adjustment was solved, but a loop closure corrected the map
	 * meanwhile, so its result was dropped. */
	bool baDiscarded{false};
	/** Wall time of each step, in order: "cull", "triangulate", "fuse", "ba_build", "ba_solve",
	 * "ba_apply", "cull_keyframes" (sequential mode builds, solves and applies as "ba"). */
	std::vector<std::pair<std::string, double>> stageSeconds;
};

class LocalMapper
{
   public:
	LocalMapper(SparseMap& map, const LocalMapperOptions& opts, const MatcherOptions& matcher);

	/** Processes a keyframe just created by the Tracker. In threaded mode the caller passes
	 * its lock on map.mutex() (held on entry and on return): the bundle adjustment is then
	 * solved with the lock released, so tracking goes on meanwhile. */
	LocalMappingReport process(KeyFrameId kf, const PinholeIntrinsics& K, std::unique_lock<std::mutex>* mapLock = nullptr);

	/** Projects landmarks `lms` into keyframe `target`, merging duplicates and adding missing
	 * observations (used after a loop closure to join both sides of the loop). Returns the
	 * number of landmarks fused. */
	int fuseLandmarks(KeyFrameId target, const std::vector<LandmarkId>& lms, const PinholeIntrinsics& K);

   private:
	int cullRecentLandmarks(KeyFrameId current);
	/** New landmarks from keypoints without one, matched with neighbour keyframes. */
	int triangulateNew(KeyFrameId kf, const PinholeIntrinsics& K);
	void fuse(KeyFrameId kf, const PinholeIntrinsics& K, LocalMappingReport& rep);
	/** Projects `lms` into keyframe `target`; merges duplicates, adds missing observations. */
	void fuseInto(KeyFrameId target, const std::vector<LandmarkId>& lms, const PinholeIntrinsics& K, LocalMappingReport& rep);
	int cullKeyFrames(KeyFrameId current);

	SparseMap& m_map;
	LocalMapperOptions m_opts;
	MatcherOptions m_matcher;
	std::deque<LandmarkId> m_recent;
};

}  // namespace keygrid::sfm
