#pragma once
/** \file HocFrontend.h
 * How the tracker uses the Histograms of Oriented Cameras (source paper 2; the histogram and
 * its bins are keygrid::maps::HocHistogram / HocGeometry, the rule is written there):
 *  - selection: a landmark takes part in data association and pose estimation only while the
 *    weight of the bin the current camera falls into exceeds select_threshold;
 *  - update, once per tracked frame at the estimated pose: landmarks matched as inliers get
 *    +1 in the camera's bin; landmarks of the local map that project into the image within the
 *    visible depth range, are not occluded according to the depth image (no closer surface
 *    measured at their pixel; a pixel without depth reading does not occlude: an occluder would
 *    be nearer than the point, hence in range), and were not matched get -1 (with
 *    decrement_needs_keypoint: only when the frame has a keypoint in the landmark's search
 *    window; otherwise the miss carries no information and n is left alone). Landmarks that
 *    were excluded by the selection are still searched for (without entering the pose) so
 *    that an object that re-appears earns its points back;
 *  - pruning: a landmark whose largest bin weight falls below prune_threshold is erased.
 * A landmark's histogram starts with +1 in the bin of every keyframe that observes it.
 */
#include <keygrid/maps/HocGeometry.h>
#include <keygrid/maps/HocHistogram.h>
#include <keygrid/sfm/Matcher.h>
#include <keygrid/sfm/PoseOptimizer.h>
#include <keygrid/sfm/SparseMap.h>

#include <vector>

namespace keygrid::sfm
{
/** Counters of one frame's HOC update. */
struct HocUpdateStats
{
	int incremented{0}, decremented{0}, occluded{0}, recovered{0}, pruned{0};
	/** Misses not counted because no keypoint was detected in the search window
	 * (decrement_needs_keypoint). */
	int undetected{0};
	/** Of the decrements, those counted only because the place was seen through (no keypoint
	 * in the window; decrement_needs_keypoint). */
	int seenThrough{0};
};

class HocFrontend
{
   public:
	explicit HocFrontend(const maps::HocOptions& opts);

	const maps::HocOptions& options() const { return m_opts; }
	const maps::HocGeometry& geometry() const { return m_geom; }

	/** Whether lm may be used from a camera centred at c (seeds an untouched histogram):
	 * p(n) > select_threshold in c's bin; with `fallback`, p(n) > min(select_threshold, p(0)),
	 * i.e. no more misses than matches there (the tracker's retry, see Tracker::track). */
	bool usable(Landmark& lm, const SparseMap& map, const Eigen::Vector3d& c, bool fallback = false) const;
	/** True when the fallback selection admits more points than the normal one. */
	bool hasFallback() const { return m_opts.selectThreshold > m_opts.weight(0); }

	/** One frame's update and pruning. `matched`: the final inlier landmark of each keypoint
	 * (kNoLandmark if none); `visible`: projections of the local-map landmarks that were
	 * candidates for matching; `excluded`: visible ones the selection kept out; `depth`:
	 * the frame's depth image [m] (empty: nothing is decremented).
	 * Excluded landmarks found again by a guided search at the final pose are counted as
	 * recovered (+1) when the match also passes fitsPose(), as the pose's inliers did. */
	HocUpdateStats update(
		SparseMap& map, const FrameFeatures& f, const std::vector<LandmarkId>& matched,
		const std::vector<ProjectedLandmark>& visible, const std::vector<ProjectedLandmark>& excluded,
		const cv::Mat& depth, const Eigen::Vector3d& cameraCentre, float searchRadius,
		const MatcherOptions& matcherOpts) const;

	/** An untouched histogram gets initial_count in the bin of the keyframe that created the
	 * point (the oldest one observing it if that was culled). Later observations that local
	 * mapping adds in other keyframes are not counted (see the .cpp). */
	void seed(Landmark& lm, const SparseMap& map) const;
	/** +1 in keyframe kf's bin for each of its points: the map-initialization keyframe, whose
	 * points are all there is to track the next frame with (with select_threshold above
	 * p(initial_count) a new point otherwise needs one confirming match first). */
	void confirmInitialMap(SparseMap& map, KeyFrameId kf) const;
	/** Whether keypoint kp of f fits the projection p at the final pose: the pose refinement's
	 * chi-square inlier test (reprojection at the keypoint's level, plus the virtual disparity
	 * when both depths are known; the gate options of setResidualGate()). */
	bool fitsPose(const FrameFeatures& f, int kp, const ProjectedLandmark& p) const;

	/** True when the depth image shows a surface in front of the predicted depth at (u, v)
	 * (the point is hidden); false also when there is no valid depth there. */
	bool occluded(const cv::Mat& depth, float u, float v, float predictedDepth) const;
	/** True when the depth image reads a surface behind the predicted depth by more than the
	 * occlusion tolerance at (u, v) and at the 8 samples 3 px around it (all valid): the point's
	 * place is seen through, it moved or vanished. Such a miss counts even with
	 * decrement_needs_keypoint. */
	bool seenThrough(const cv::Mat& depth, float u, float v, float predictedDepth) const;
	/** True when f has a keypoint in p's search window: within radius * scale(level) of the
	 * projection at the predicted level +-1, the keypoints searchByProjection compares. */
	static bool keypointInWindow(const FrameFeatures& f, const ProjectedLandmark& p, float radius);
	/** True when the depth image has a valid value at (u, v). */
	static bool hasDepth(const cv::Mat& depth, float u, float v);

	/** Residual model and chi-square bounds of fitsPose() (the tracker passes its pose
	 * refinement's options; default-constructed until then). */
	void setResidualGate(const PoseOptimizerOptions& o) { m_gate = o; }

   private:
	/** m_opts.weight(n), from a table for |n| <= count_limit (counts are clamped to it). */
	double weight(int n) const;

	PoseOptimizerOptions m_gate;
	maps::HocOptions m_opts;
	maps::HocGeometry m_geom;
	std::vector<double> m_weights;  // weight(n) at index n + count_limit
};

}  // namespace keygrid::sfm
