#pragma once
/** \file LocalMapper.h
 * Refines the map around each new keyframe: covisibility, culling of weak new landmarks,
 * fusion of duplicated landmarks with the neighbours, local bundle adjustment, and culling of
 * redundant keyframes.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/sfm/LocalBundleAdjuster.h>
#include <keygrid/sfm/Matcher.h>
#include <keygrid/sfm/SparseMap.h>

#include <chrono>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace keygrid::sfm
{
struct LocalMapperOptions : public core::FieldTableOptions<LocalMapperOptions>
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

	/** The [mapping] keys, the local bundle adjustment's included. */
	core::OptionFields fields();
	/** Throws std::invalid_argument naming section, key, value and rule of an invalid option. */
	void validate(const std::string& section = "mapping") const;
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

/** Local mapping of one keyframe, split where its bundle adjustment is solved (threaded mode):
 * LocalMapper::prepare() and LocalMapper::complete() read and write the map, so their caller
 * holds SparseMap::mutex(); solve() works on the pass's own copies, so the caller releases
 * that lock around it and tracking goes on meanwhile. */
class LocalMappingPass
{
   public:
	/** Solves the local bundle adjustment, if prepare() built one; touches no map. */
	void solve();

   private:
	friend class LocalMapper;
	explicit LocalMappingPass(KeyFrameId kf);
	/** Ends stage `stage` of the report's stageSeconds and starts the next. */
	void lap(const char* stage);

	KeyFrameId m_kf;
	LocalMappingReport m_report;
	/** The map had another keyframe: the steps after culling ran, and keyframes are culled */
	bool m_refined{false};
	std::optional<BundleAdjustment> m_ba;
	std::uint64_t m_correctionsAtBuild{0};  //!< SparseMap::corrections() when m_ba was built
	std::chrono::steady_clock::time_point m_stageStart;
};

class LocalMapper
{
   public:
	LocalMapper(SparseMap& map, const LocalMapperOptions& opts, const MatcherOptions& matcher);

	/** Processes a keyframe just created by the Tracker, in one go (sequential mode; the
	 * caller holds the map's lock when other threads use the map). */
	LocalMappingReport process(KeyFrameId kf, const PinholeIntrinsics& K);

	/** The same as process() in phases (LocalMappingPass): everything up to the bundle
	 * adjustment, which is copied out of the map... */
	LocalMappingPass prepare(KeyFrameId kf, const PinholeIntrinsics& K);
	/** ...and, after LocalMappingPass::solve(), its result written back and keyframes culled.
	 * A loop correction since prepare() (SparseMap::corrections()) drops the result
	 * (LocalMappingReport::baDiscarded): it was solved in the old frame. */
	LocalMappingReport complete(LocalMappingPass pass);

	/** Projects landmarks `lms` into keyframe `target`, merging duplicates and adding missing
	 * observations (used after a loop closure to join both sides of the loop). Returns the
	 * number of landmarks fused. */
	int fuseLandmarks(KeyFrameId target, const std::vector<LandmarkId>& lms, const PinholeIntrinsics& K);

   private:
	/** Up to the bundle adjustment: probation and culling of new landmarks, then, when the map
	 * has another keyframe, triangulation, fusion and covisibility (pass.m_refined). */
	void refine(LocalMappingPass& pass, const PinholeIntrinsics& K);
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
