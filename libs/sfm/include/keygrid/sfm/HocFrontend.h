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
};

class HocFrontend
{
   public:
	explicit HocFrontend(const maps::HocOptions& opts);

	const maps::HocOptions& options() const { return m_opts; }
	const maps::HocGeometry& geometry() const { return m_geom; }

	/** Whether lm may be used from a camera centred at c (seeds an untouched histogram). */
	bool usable(Landmark& lm, const SparseMap& map, const Eigen::Vector3d& c) const;

	/** One frame's update and pruning. `matched`: the final inlier landmark of each keypoint
	 * (kNoLandmark if none); `visible`: projections of the local-map landmarks that were
	 * candidates for matching; `excluded`: visible ones the selection kept out; `depth`:
	 * the frame's depth image [m] (empty: nothing is decremented).
	 * Excluded landmarks found again by a guided search are counted as recovered (+1). */
	HocUpdateStats update(
		SparseMap& map, const FrameFeatures& f, const std::vector<LandmarkId>& matched,
		const std::vector<ProjectedLandmark>& visible, const std::vector<ProjectedLandmark>& excluded,
		const cv::Mat& depth, const Eigen::Vector3d& cameraCentre, float searchRadius,
		const MatcherOptions& matcherOpts) const;

	/** Adds +1 at the bin of each observing keyframe when the histogram is untouched. */
	void seed(Landmark& lm, const SparseMap& map) const;

	/** True when the depth image shows a surface in front of the predicted depth at (u, v)
	 * (the point is hidden); false also when there is no valid depth there. */
	bool occluded(const cv::Mat& depth, float u, float v, float predictedDepth) const;
	/** True when f has a keypoint in p's search window: within radius * scale(level) of the
	 * projection at the predicted level +-1, the keypoints searchByProjection compares. */
	static bool keypointInWindow(const FrameFeatures& f, const ProjectedLandmark& p, float radius);
	/** True when the depth image has a valid value at (u, v). */
	static bool hasDepth(const cv::Mat& depth, float u, float v);

   private:
	maps::HocOptions m_opts;
	maps::HocGeometry m_geom;
};

}  // namespace keygrid::sfm
