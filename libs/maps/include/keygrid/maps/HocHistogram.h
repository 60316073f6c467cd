#pragma once
/** \file HocHistogram.h
 * The per-point Histogram of Oriented Cameras and its options (source paper 2).
 *
 * Update rule: a bin (see HocGeometry) holds an integer n, n += 1 when the point was matched by
 * a camera in that bin, n -= 1 when it should have been seen from there (projects into the
 * image, inside the depth range, not occluded according to the depth image) but was not
 * (optionally only when the feature detector found a keypoint where the point was searched
 * for, see decrementNeedsKeypoint); n is clamped to [-count_limit, count_limit] so that a
 * point whose object re-appears can recover.
 * Weight of a bin: p(n) = 1 / (1 + exp(-gain * (n - offset))), monotone in n, so the maximum
 * weight of a point is p(max_bins n). A bin never observed has n = 0.
 * Use: a point takes part in data association and pose estimation from a camera in bin b only
 * while p(n_b) > select_threshold; it is removed from the map when max_b p(n_b) < prune_threshold.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>

#include <cstdint>
#include <string>
#include <vector>

namespace keygrid::maps
{
struct HocOptions : public core::FieldTableOptions<HocOptions>
{
	/** Use the HOC in the frontend; false gives the standard (static-world) system, for
	 * comparisons (Default: false) */
	bool enabled{false};
	/** Shell radii [m], increasing (Default: 1 2 4) */
	std::vector<double> radii{1.0, 2.0, 4.0};
	/** Icosahedron subdivisions: 0 -> 20 faces per shell, s -> 20 * 4^s (Default: 0) */
	int subdivisions{0};
	/** Sigmoid gain and offset of the bin weight p(n) (Default: 1, 0) */
	double sigmoidGain{1.0}, sigmoidOffset{0.0};
	/** A point is used for matching from bin b while p(n_b) > this (Default: 0.8, i.e. with
	 * gain 1 and offset 0: n >= 2, so a new point (initial_count 1) takes part in pose
	 * estimation only after one match at a final pose has confirmed it; the tracker still
	 * searches for excluded points there, see keygrid::sfm::HocFrontend) */
	double selectThreshold{0.8};
	/** A point is removed when its largest bin weight is below this. Bins never updated have
	 * n = 0, so the threshold must exceed p(0) for pruning to act (Default: 0.6, i.e. no bin
	 * with n >= 1 left) */
	double pruneThreshold{0.6};
	/** |n| limit (Default: 20) */
	int countLimit{20};
	/** n given to a new point in the bin of the keyframe that created it: how many net misses
	 * it survives before it has to be seen again (Default: 1) */
	int initialCount{1};
	/** Occlusion test: the point counts as hidden when the depth image measures a surface
	 * closer than predicted by more than abs + rel * depth [m] (Default: 0.05 m, 0.03) */
	double occlusionToleranceAbs{0.05}, occlusionToleranceRel{0.03};
	/** Depth range in which a point is expected to be seen [m]; keep the maximum inside the
	 * sensor's range (Default: 0.3 .. 4.0) */
	double visibleDepthMin{0.3}, visibleDepthMax{4.0};
	/** Count a miss (n -= 1) only when the frame has a keypoint in the landmark's search window
	 * (the area and pyramid levels the projection matcher compares it with). A miss without any
	 * keypoint there says nothing about the point: a static point is re-detected in only about
	 * half of the frames (blur, contrast, the per-cell feature budget), and counting those
	 * misses makes n drift down by 2q - 1 per frame for a point matched with probability q < 1/2.
	 * true keeps static maps accurate but prunes less (larger maps); see doc/hoc.md. Used by
	 * the tracker (keygrid::sfm::HocFrontend); CHOCPointsMap's depth-scan insertion has no
	 * keypoints and ignores it (Default: true) */
	bool decrementNeedsKeypoint{true};

	/** Bin weight p(n). */
	double weight(int n) const;
	/** Throws std::invalid_argument naming the first invalid field. */
	/** The HOC keys ([hoc], and the hocPointsMap plugin's creationOpts). */
	keygrid::core::OptionFields fields();
	/** Throws std::invalid_argument naming section, key, value and rule of an invalid option. */
	void validate(const std::string& section = "hoc") const;
};

/** Counts of one point; storage is allocated on the first update (an untouched point costs
 * one empty vector). */
class HocHistogram
{
   public:
	/** n of a bin (0 when never updated). */
	int count(int bin) const { return m_n.empty() ? 0 : m_n.at(static_cast<std::size_t>(bin)); }
	/** n_bin += delta, clamped to [-limit, limit]. */
	void add(int bin, int delta, int limit, int numBins);
	/** Largest n over all bins (0 for an untouched histogram). */
	int maxCount() const;
	bool touched() const { return !m_n.empty(); }
	const std::vector<std::int16_t>& counts() const { return m_n; }
	/** Replaces the counts (deserialization); size must be 0 or the number of bins. */
	void setCounts(std::vector<std::int16_t> n) { m_n = std::move(n); }

   private:
	std::vector<std::int16_t> m_n;
};

}  // namespace keygrid::maps
