#pragma once
/** \file MetricScale.h
 * Metric scale for a monocular run from the camera's known height above the floor: when the
 * map has enough keyframes, sfm::CameraHeightScaleEstimator measures its scale (metres per map
 * unit) and the map is rescaled by it; from then on the estimate is repeated every
 * reestimate_every keyframes and applied again, so the map stays metric as it grows and its
 * scale drifts. Until the first estimate succeeds it is tried at every new keyframe; later ones
 * search the floor along the newest stretch of the path (window_path_length). While that stretch
 * is the whole map, the whole map is rescaled; once the map is longer, only the stretch is (and
 * a factor far from 1 is refused): its scale ramps from 1 at its oldest keyframe to the factor at its
 * middle and stays there to the newest keyframe, so the parts made metric before keep their
 * metres. The map alone is moved
 * here; the caller (slam::System) moves what refers to it (tracker, frames, maps).
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>
#include <keygrid/sfm/CameraHeightScale.h>
#include <keygrid/sfm/SparseMap.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace keygrid::slam
{
/** [camera_height_scale]: the estimator's keys and how often it runs. */
struct MetricScaleOptions : public core::FieldTableOptions<MetricScaleOptions>
{
	/** camera_height (0 = unknown: the monocular map keeps an arbitrary scale) and the floor
	 * search (sfm::CameraHeightScaleOptions). */
	sfm::CameraHeightScaleOptions estimator;
	/** After the first successful estimate, estimate and rescale again every this many new
	 * keyframes (Default: 10) */
	int reestimateEvery{10};
	/** The floor search runs on the map points whose observing keyframes see them under rays
	 * this far apart [deg], and on every point only when those give no estimate: a point
	 * triangulated over a short baseline (the map start's) may lie far off its surface, under
	 * the floor; 0 = every point (Default: 2 deg) */
	double minPointParallaxDeg{2.0};
	/** Once the map is metric, the floor is searched among the newest keyframes that span this
	 * much of the path [m] and the map points they observe: a monocular map's scale drifts
	 * along the path, so its floor is a plane only locally, and over the whole map of a long
	 * run the floor seen early lies above or under the floor seen late. The factor found there
	 * rescales the whole map: it is the scale where the camera is now. The first estimate uses
	 * the whole map (its units are not metres yet); 0 = always the whole map (Default: 8 m) */
	double windowPathLength{8.0};
	/** The floor search along the newest stretch of path (a metric map longer than the window)
	 * takes a plane with up to this x its least support of points under it, where the searches
	 * over the whole map take max_below_share: along a long path a monocular map keeps a few
	 * per cent of stray points under its floor, and the stricter bound refuses most windows (a
	 * desk top is still refused: the points under it form a plane of their own,
	 * maps::estimateLowestFloorPlane). A metric map whose path is still shorter than the window
	 * is searched with the stricter bound first and, when that finds no clear floor, with this
	 * one. The map's first estimate, on keyframes whose scale is not known yet, keeps the
	 * stricter bound (Default: 3) */
	double windowMaxBelowShare{3.0};
	/** The maps' floor (floorPlane()) is the plane through the keyframe centres, camera_height
	 * under it, when the centres lie this close to one plane (RMS distance) [m]: a camera at a
	 * fixed height on a robot draws the floor's orientation with its whole path, where the
	 * floor points give it only near the newest stretch (a small tilt there lifts or sinks the
	 * floor metres away). Otherwise (a hand-held camera) the floor of the estimate; 0 = always
	 * that one (Default: 0.02 m) */
	double pathFloorMaxRms{0.02};
	/** ... and when the path spreads this far across its main direction (the standard deviation
	 * of the centres along the plane's second axis: a straight path leaves the plane free to
	 * roll about it) [m] (Default: 1 m) */
	double pathFloorMinSpread{1.0};
	/** Rescale the whole map by every estimate, even once the map is longer than
	 * window_path_length, instead of the window only (see the file comment): a drift corrected
	 * where the camera is now also rescales what was already metric (Default: false) */
	bool rescaleWholeMap{false};
	/** An estimate along the newest stretch that changes the scale by more than this share is
	 * refused: the scale drifts little between two estimates, and such a factor comes from a
	 * large plane above the floor (a desk top whose floor was hidden) taken for the floor;
	 * unless an estimate over the whole map agrees with it (within this share), which then
	 * rescales the whole map (its scale was off before the stretch too).
	 * Estimates over the whole map (the first ones) are not bound: a first estimate on a few
	 * keyframes can be far off, and the next ones must be able to undo it. The one exception
	 * is the whole-map search of a metric map repeated with window_max_below_share (its strict
	 * search found no clear floor): it is bound too, as its generous bound may take a plane of
	 * stray points. A persistent shrink is taken after all (windowPersistentShrink); 0 = no
	 * bound (Default: 0.1) */
	double windowMaxChange{0.1};
	/** A refused change that makes the map smaller (factor below 1 - window_max_change: the
	 * floor found farther below the cameras than camera_height, which no plane above the floor
	 * can cause: the map grew) is taken when this many consecutive estimates
	 * along the newest stretch, this one included, were refused for it and agree within
	 * window_max_change / 2 (their largest and smallest factor): a drift the whole map cannot
	 * confirm, its earlier part being at another scale. 0 = never (Default: 3) */
	int windowPersistentShrink{3};
	/** After the run's final bundle adjustment, estimate the scale once more and rescale the
	 * whole map (MetricScale::finalEstimate): that adjustment reshapes the map, and its
	 * overall scale is free (a map without depth) (Default: true) */
	bool finalEstimate{true};

	bool enabled() const { return estimator.cameraHeight > 0; }
	core::OptionFields fields();
	/** Throws std::invalid_argument naming section, key, value and rule of an invalid option. */
	void validate(const std::string& section = "camera_height_scale") const;
};

class MetricScale
{
   public:
	/** Throws std::invalid_argument when the options are invalid or camera_height is 0. */
	explicit MetricScale(const MetricScaleOptions& opts);

	/** What an applied estimate did to the map. */
	struct Rescale
	{
		/** The estimate's factor: metres per map unit where the camera is now */
		double factor{1.0};
		/** Empty: the whole map was scaled by `factor` about the world origin
		 * (SparseMap::rescale). Else the keyframes of the newest stretch of path, which alone
		 * moved: their new poses, and the factor their landmarks grew by about them (as a Sim(3)
		 * loop correction, loop::applySim3Corrections) */
		std::map<sfm::KeyFrameId, mrpt::poses::CPose3D> newPoses;
		std::map<sfm::KeyFrameId, double> newScales;
		bool wholeMap() const { return newScales.empty(); }
	};
	/** When an estimate is due (see the file comment): estimates the scale of `map` (its
	 * keyframes and landmarks) and, when the estimate succeeds, rescales the map (all of it,
	 * or its newest stretch) and says how; nullopt when nothing was applied. The caller holds
	 * the map's lock. */
	std::optional<Rescale> update(sfm::SparseMap& map);
	/** After the run's final bundle adjustment: estimates the map's scale and rescales the
	 * whole map when the change is at most window_max_change; nullopt otherwise, and for a map
	 * not metric yet. A path longer than 1.5 window_path_length is cut into stretches of
	 * window_path_length starting every half of it, each searched as the newest stretch is
	 * during the run; the factor is their median, when at least two and at least half of them
	 * found a floor. Otherwise the whole map is searched (when the strict search finds no clear
	 * floor, with window_max_below_share). The caller holds the map's lock. */
	std::optional<Rescale> finalEstimate(sfm::SparseMap& map);
	/** The map's scale changed in places (a Sim(3) loop correction, which keeps the units of the
	 * map's first keyframe): the next update() estimates, whenever the last estimate was. The
	 * caller holds the map's lock. */
	void requestEstimate() { m_lastEstimateAt.reset(); }
	/** The map is metric and an estimate was requested that no update() has run yet. */
	bool estimateRequested() const { return metric() && !m_lastEstimateAt; }

	struct Stats
	{
		int estimates{0};  //!< estimates run
		int applied{0};  //!< of them, successful and applied
		/** Product of the factors applied: metres per unit of the map as it started */
		double totalFactor{1.0};
		/** Factor of the last applied estimate (1: the map already was at that scale) */
		double lastFactor{1.0};
		std::string lastMessage;  //!< the last estimate's result text
	};
	const Stats& stats() const { return m_stats; }
	/** One line per estimate run: the newest keyframe id, the keyframes searched, and the
	 * result (the factor applied, or why none was); the first kMaxLogLines estimates. */
	const std::vector<std::string>& log() const { return m_log; }
	static constexpr std::size_t kMaxLogLines = 1000;
	/** The floor plane of the last applied estimate, n . p + offset = 0 in the map as it is
	 * now (metres; n unit, towards the cameras): the plane under the camera path when the path
	 * is level and wide enough (pathFloorMaxRms, pathFloorMinSpread), else the floor the
	 * estimate found among the map points; nullopt before the first. */
	struct FloorPlane
	{
		Eigen::Vector3d normal;
		double offset{0};
	};
	const std::optional<FloorPlane>& floorPlane() const { return m_floorPlane; }
	/** The map is in metres: an estimate was applied. */
	bool metric() const { return m_stats.applied > 0; }

   private:
	/** The estimator on `keyframes` (ascending ids) and the map points they observe (every
	 * point when they are the whole map): the well-triangulated points first, then all. */
	sfm::CameraHeightScaleResult estimateOver(
		const sfm::SparseMap& map, const std::vector<sfm::KeyFrameId>& keyframes,
		const sfm::CameraHeightScaleEstimator& estimator, std::size_t* pointsSearched = nullptr) const;

	/** finalEstimate() of a long map: the estimate of the stretch (ascending ids each) with the
	 * median factor, its floor offset set for `all` the map's keyframes; nullopt when fewer
	 * than two or than half of the stretches found a floor. `how` says what was found, for
	 * the log. */
	std::optional<sfm::CameraHeightScaleResult> medianOverStretches(
		const sfm::SparseMap& map, const std::vector<std::vector<sfm::KeyFrameId>>& stretches,
		const std::vector<sfm::KeyFrameId>& all, std::string& how) const;

	/** Counts the estimate `r` over `window` (all keyframes when wholeMap) and, when it
	 * succeeded, applies it (the whole map, or the window alone) and sets the floor plane; logs
	 * logHead and the result. */
	std::optional<Rescale> conclude(
		sfm::SparseMap& map, const sfm::CameraHeightScaleResult& r, const std::vector<sfm::KeyFrameId>& window, bool wholeMap,
		const std::string& logHead);

	/** A window estimate `f` that window_max_change refuses as a shrink is taken: the
	 * windowPersistentShrink - 1 refusals before it and f agree within window_max_change / 2. */
	bool persistentShrink(double f) const;

	MetricScaleOptions m_opts;
	sfm::CameraHeightScaleEstimator m_estimator;
	sfm::CameraHeightScaleEstimator m_windowEstimator;  //!< with windowMaxBelowShare
	/** Newest keyframe id at the last estimate (ids only grow: culling does not reset it) */
	std::optional<sfm::KeyFrameId> m_lastEstimateAt;
	Stats m_stats;
	std::optional<FloorPlane> m_floorPlane;  //!< see floorPlane()
	std::vector<std::string> m_log;  //!< see log()
	/** The factors of the consecutive estimates refused for shrinking the map beyond
	 * window_max_change, oldest first (see windowPersistentShrink); cleared by any other
	 * outcome of an estimate but a failed one. */
	std::vector<double> m_refusedShrinks;
};

}  // namespace keygrid::slam
