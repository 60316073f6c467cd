#include <keygrid/loop/Sim3MapCorrection.h>
#include <keygrid/slam/MetricScale.h>
#include <mrpt/config/CConfigFileBase.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

namespace keygrid::slam
{
core::OptionFields MetricScaleOptions::fields()
{
	core::OptionFields f = estimator.fields();
	f.add("min_point_parallax_deg", minPointParallaxDeg, "map points seen under rays less far apart are left out of the floor search [deg]; 0 = all", core::OptionRule::fromBelow(0, 90));
	f.add("window_max_below_share", windowMaxBelowShare, "once the map is metric, the floor search along the newest stretch (and, when the stricter bound finds no clear floor, over the whole map) takes a plane with up to this x its least support of points under it", core::OptionRule::atLeast(0));
	f.add("window_path_length", windowPathLength, "once metric, the floor is searched along this much of the newest path [m]; 0 = whole map", core::OptionRule::atLeast(0));
	f.add("path_floor_max_rms", pathFloorMaxRms, "the maps' floor is the plane through the keyframe centres, camera_height under it, when they lie this close to one plane [m]; 0 = the floor points' plane", core::OptionRule::atLeast(0));
	f.add("path_floor_min_spread", pathFloorMinSpread, "... and when the path spreads this far across its main direction [m]", core::OptionRule::atLeast(0));
	f.add("rescale_whole_map", rescaleWholeMap, "every estimate rescales the whole map, not only the newest window_path_length of path");
	f.add("window_max_change", windowMaxChange, "an estimate along the newest stretch (or a metric map's whole-map search repeated with window_max_below_share) changing the scale by more than this share is refused; 0 = no bound", core::OptionRule::atLeast(0));
	f.add("window_persistent_shrink", windowPersistentShrink, "a refused change shrinking the map (floor farther below than camera_height) is taken when this many consecutive estimates agree on it within window_max_change / 2; 0 = never", core::OptionRule::atLeast(0));
	f.add("final_estimate", finalEstimate, "after the final bundle adjustment (which leaves a monocular map's scale free), estimate the scale once more and rescale the whole map: the median over overlapping stretches of window_path_length when the path is longer than 1.5 of it, else over the whole map");
	f.add("reestimate_every", reestimateEvery, "after the first estimate, estimate and rescale again every this many keyframes", core::OptionRule::positive());
	return f;
}

void MetricScaleOptions::validate(const std::string& s) const
{
	core::validateFields(*this, s);
	estimator.validate(s);
}

namespace
{
/** The newest keyframes (ascending ids) whose centres span `pathLength` of the path, in id
 * order; every keyframe when pathLength is 0 or the path is shorter. */
std::vector<sfm::KeyFrameId> estimateWindow(const sfm::SparseMap& map, double pathLength)
{
	std::vector<sfm::KeyFrameId> ids;
	ids.reserve(map.numKeyFrames());
	double travelled = 0;
	std::optional<Eigen::Vector3d> next;
	for (auto it = map.keyframes().rbegin(); it != map.keyframes().rend(); ++it)
	{
		const Eigen::Vector3d c = sfm::translationOf(it->second.T_world_cam);
		if (next) travelled += (*next - c).norm();
		if (pathLength > 0 && travelled > pathLength) break;
		ids.push_back(it->first);
		next = c;
	}
	std::reverse(ids.begin(), ids.end());
	return ids;
}

/** Overlapping stretches of the path, each `length` long (keyframe centres in id order),
 * starting every length / 2, the last ending at the newest keyframe; none when the path is at
 * most 1.5 x length long. Ascending ids in each. */
std::vector<std::vector<sfm::KeyFrameId>> pathStretches(const sfm::SparseMap& map, double length)
{
	std::vector<std::pair<sfm::KeyFrameId, double>> along;  // keyframe, path length up to it
	std::optional<Eigen::Vector3d> prev;
	double travelled = 0;
	for (const auto& [id, kf] : map.keyframes())
	{
		const Eigen::Vector3d c = sfm::translationOf(kf.T_world_cam);
		if (prev) travelled += (c - *prev).norm();
		along.emplace_back(id, travelled);
		prev = c;
	}
	std::vector<std::vector<sfm::KeyFrameId>> out;
	if (!(length > 0) || travelled <= 1.5 * length) return out;
	const double step = 0.5 * length;
	for (double start = 0;; start += step)
	{
		const double from = std::min(start, travelled - length);
		out.emplace_back();
		for (const auto& [id, s] : along)
			if (s >= from && s <= from + length) out.back().push_back(id);
		if (from + length >= travelled) break;
	}
	return out;
}

/** Whether a keyframe of the (sorted) window observes the landmark. */
bool observedFrom(const sfm::Landmark& lm, const std::vector<sfm::KeyFrameId>& window)
{
	for (const auto& obs : lm.observations)
		if (std::binary_search(window.begin(), window.end(), obs.first)) return true;
	return false;
}

/** A plane through the path steeper than this against the floor points' plane is no floor. */
constexpr double kMaxPathFloorTiltDeg = 5.0;

/** The floor under a camera moving at camera_height: the least-squares plane through every
 * keyframe centre (its normal is the direction of least spread of the centres, turned to
 * `up`), moved camera_height down; nullopt with the reason in `why` when the path is not level
 * enough (RMS distance to the plane), too narrow, or tilted against `up`. */
std::optional<MetricScale::FloorPlane> floorUnderThePath(
	const sfm::SparseMap& map, const Eigen::Vector3d& up, const MetricScaleOptions& o, std::string& why)
{
	if (!(o.pathFloorMaxRms > 0))
	{
		why = "floor from the map points";
		return std::nullopt;
	}
	Eigen::Vector3d mean = Eigen::Vector3d::Zero();
	for (const auto& [id, kf] : map.keyframes()) mean += sfm::translationOf(kf.T_world_cam);
	mean /= static_cast<double>(map.numKeyFrames());
	Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
	for (const auto& [id, kf] : map.keyframes())
	{
		const Eigen::Vector3d d = sfm::translationOf(kf.T_world_cam) - mean;
		cov += d * d.transpose();
	}
	cov /= static_cast<double>(map.numKeyFrames());
	const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);  // eigenvalues ascending
	const double rms = std::sqrt(std::max(0.0, eig.eigenvalues()(0))), spread = std::sqrt(std::max(0.0, eig.eigenvalues()(1)));
	Eigen::Vector3d n = eig.eigenvectors().col(0);
	if (n.dot(up) < 0) n = -n;
	const double tiltDeg = std::acos(std::min(1.0, n.dot(up.normalized()))) * 180.0 / M_PI;
	char b[160];
	std::snprintf(b, sizeof(b), "camera path: %.1f mm off a plane, %.2f m wide, %.2f deg to the floor points' plane", rms * 1e3, spread, tiltDeg);
	why = b;
	if (rms > o.pathFloorMaxRms || spread < o.pathFloorMinSpread || tiltDeg > kMaxPathFloorTiltDeg)
	{
		why = "floor from the map points (" + why + ")";
		return std::nullopt;
	}
	why = "floor under the " + why;
	return MetricScale::FloorPlane{n, o.estimator.cameraHeight - n.dot(mean)};
}

/** Rescales the window's keyframes (ascending ids, the newest stretch of path) and their
 * landmarks by a ramp: keyframe i of the N takes the scale f^min(1, i / (N / 2)), 1 at the
 * oldest (joined to the map before it) and the estimate's f from the middle keyframe on, whose
 * height the estimate measured (a median over the window). The path is re-chained in id order,
 * each step scaled by the geometric mean of its ends' scales; orientations stay. */
MetricScale::Rescale rescaleWindow(sfm::SparseMap& map, const std::vector<sfm::KeyFrameId>& window, double f)
{
	const auto oldS = loop::keyFrameSims(map);
	std::map<sfm::KeyFrameId, loop::Sim3> newS;
	const double half = std::max(1.0, 0.5 * static_cast<double>(window.size() - 1));
	MetricScale::Rescale out;
	out.factor = f;
	Eigen::Vector3d prevOld = oldS.at(window.front()).t, prevNew = prevOld;
	double prevScale = 1.0;
	for (std::size_t i = 0; i < window.size(); i++)
	{
		const loop::Sim3& S = oldS.at(window[i]);
		const double s = std::pow(f, std::min(1.0, static_cast<double>(i) / half));
		const Eigen::Vector3d c = prevNew + std::sqrt(s * prevScale) * (S.t - prevOld);
		newS[window[i]] = loop::Sim3{S.q, c, s};
		out.newScales[window[i]] = s;
		prevOld = S.t;
		prevNew = c;
		prevScale = s;
	}
	loop::applySim3Corrections(map, oldS, newS);
	for (const sfm::KeyFrameId id : window) out.newPoses[id] = map.keyframe(id).T_world_cam;
	return out;
}

/** The window's median keyframe height along n above the origin plane n . p = 0. */
double medianHeight(const sfm::SparseMap& map, const std::vector<sfm::KeyFrameId>& window, const Eigen::Vector3d& n)
{
	std::vector<double> h;
	for (const sfm::KeyFrameId id : window) h.push_back(n.dot(sfm::translationOf(map.keyframe(id).T_world_cam)));
	std::nth_element(h.begin(), h.begin() + static_cast<std::ptrdiff_t>(h.size() / 2), h.end());
	return h[h.size() / 2];
}

sfm::CameraHeightScaleOptions withMaxBelowShare(sfm::CameraHeightScaleOptions o, double share)
{
	o.maxBelowShare = share;
	return o;
}
}  // namespace

sfm::CameraHeightScaleResult MetricScale::estimateOver(
	const sfm::SparseMap& map, const std::vector<sfm::KeyFrameId>& keyframes, const sfm::CameraHeightScaleEstimator& estimator,
	std::size_t* pointsSearched) const
{
	std::vector<mrpt::poses::CPose3D> poses;
	poses.reserve(keyframes.size());
	for (const sfm::KeyFrameId id : keyframes) poses.push_back(map.keyframe(id).T_world_cam);
	// The well-triangulated points first; when they give no estimate (too few yet, or no clear
	// floor among them), every point.
	std::vector<Eigen::Vector3d> points, all;
	const double minCos = std::cos(m_opts.minPointParallaxDeg * M_PI / 180.0);
	const bool wholeMap = keyframes.size() == map.numKeyFrames();
	for (const auto& [id, lm] : map.landmarks())
	{
		if (!wholeMap && !observedFrom(lm, keyframes)) continue;
		all.push_back(lm.p_world);
		if (!(sfm::largestParallaxCos(map, lm) > minCos)) points.push_back(lm.p_world);
	}
	auto r = estimator.estimate(poses, points);
	if (!r.ok && points.size() < all.size()) r = estimator.estimate(poses, all);
	if (pointsSearched) *pointsSearched = all.size();
	return r;
}

std::optional<sfm::CameraHeightScaleResult> MetricScale::medianOverStretches(
	const sfm::SparseMap& map, const std::vector<std::vector<sfm::KeyFrameId>>& stretches, const std::vector<sfm::KeyFrameId>& all,
	std::string& how) const
{
	/* A long map is measured stretch by stretch, as the estimates along the run measured it, and
	 * scaled by the median of the stretches' factors. The final adjustment may leave the map
	 * slightly bent (a loop's correction spread over its keyframes): then no single plane fits
	 * its floor, and one plane over the whole map takes the bend's tilt for a change of the
	 * cameras' height. Each stretch's floor is nearly flat. */
	std::vector<std::pair<double, std::size_t>> found;  // factor, stretch
	std::vector<sfm::CameraHeightScaleResult> results;
	for (std::size_t i = 0; i < stretches.size(); i++)
	{
		results.push_back(estimateOver(map, stretches[i], m_windowEstimator));
		if (results.back().ok) found.emplace_back(results.back().scale, i);
	}
	char b[200];
	std::snprintf(b, sizeof(b), "%zu stretches of %.3g m, %zu with a floor", stretches.size(), m_opts.windowPathLength, found.size());
	how = b;
	if (2 * found.size() < stretches.size() || found.size() < 2)
	{
		how += ": too few, over the whole map instead";
		return std::nullopt;
	}
	std::sort(found.begin(), found.end());
	const auto& [median, at] = found[found.size() / 2];
	auto r = results[at];
	// The median stretch's floor orientation, camera_height under the whole map's median
	// keyframe height once rescaled (conclude() scales the offset by r.scale).
	r.floorOffset = m_opts.estimator.cameraHeight / median - medianHeight(map, all, r.floorNormal);
	std::snprintf(b, sizeof(b), " (x%.4f to x%.4f): median", found.front().first, found.back().first);
	how += b;
	r.message = how + "; its stretch: " + r.message;
	return r;
}

std::optional<MetricScale::Rescale> MetricScale::finalEstimate(sfm::SparseMap& map)
{
	if (!m_opts.finalEstimate || !metric() || map.numKeyFrames() < static_cast<std::size_t>(m_opts.estimator.minKeyframes)) return std::nullopt;
	const auto all = estimateWindow(map, 0.0);
	const auto stretches = pathStretches(map, m_opts.windowPathLength);
	std::string how;
	std::optional<sfm::CameraHeightScaleResult> r;
	if (!stretches.empty()) r = medianOverStretches(map, stretches, all, how);
	std::size_t pointsSearched = 0;
	if (!r)
	{
		// A map within 1.5 stretches (or whose stretches found too few floors): one search over
		// all of it, the strict bound first.
		r = estimateOver(map, all, m_estimator, &pointsSearched);
		if (!r->ok) r = estimateOver(map, all, m_windowEstimator);
		if (!how.empty()) r->message = how + "; " + r->message;
	}
	if (r->ok && m_opts.windowMaxChange > 0 && std::abs(r->scale - 1) > m_opts.windowMaxChange)
	{
		r->ok = false;
		r->message = "refused: x" + std::to_string(r->scale) + " exceeds window_max_change; " + r->message;
	}
	return conclude(
		map, *r, all, true,
		"final map, " + std::to_string(all.size()) + " keyframes, " + (pointsSearched ? std::to_string(pointsSearched) + " points: " : ""));
}

std::optional<MetricScale::Rescale> MetricScale::conclude(
	sfm::SparseMap& map, const sfm::CameraHeightScaleResult& r, const std::vector<sfm::KeyFrameId>& window, bool wholeMap, const std::string& logHead)
{
	m_stats.estimates++;
	m_stats.lastMessage = r.message;
	std::string floorSource;
	Rescale applied;
	if (r.ok)
	{
		// The whole map while the window is all of it or when asked for; else the window alone.
		FloorPlane found{r.floorNormal, 0.0};
		if (wholeMap || m_opts.rescaleWholeMap || window.size() < 2)
		{
			map.rescale(r.scale);
			applied.factor = r.scale;
			// The plane was found in the map before the rescale: its offset scales with the map.
			found.offset = r.floorOffset * r.scale;
		}
		else
		{
			applied = rescaleWindow(map, window, r.scale);
			// The floor the estimate found, camera_height under the rescaled window.
			found.offset = m_opts.estimator.cameraHeight - medianHeight(map, window, r.floorNormal);
		}
		m_floorPlane = floorUnderThePath(map, r.floorNormal, m_opts, floorSource).value_or(found);
	}
	if (m_log.size() < kMaxLogLines)
		m_log.push_back(
			logHead + (r.ok ? "x" + std::to_string(r.scale) + (applied.wholeMap() ? " (whole map), " : " (window), ") : "") +
			r.message + (r.ok ? "; " + floorSource : ""));
	if (!r.ok) return std::nullopt;
	m_stats.applied++;
	m_stats.totalFactor *= r.scale;
	m_stats.lastFactor = r.scale;
	return applied;
}

bool MetricScale::persistentShrink(double f) const
{
	const auto k = static_cast<std::size_t>(m_opts.windowPersistentShrink);
	if (k == 0 || !(f < 1) || m_refusedShrinks.size() + 1 < k) return false;
	double lo = std::log(f), hi = lo;
	for (auto it = m_refusedShrinks.end() - static_cast<std::ptrdiff_t>(k - 1); it != m_refusedShrinks.end(); ++it)
	{
		lo = std::min(lo, std::log(*it));
		hi = std::max(hi, std::log(*it));
	}
	return hi - lo <= 0.5 * m_opts.windowMaxChange;
}

MetricScale::MetricScale(const MetricScaleOptions& opts)
	: m_opts(opts), m_estimator(opts.estimator), m_windowEstimator(withMaxBelowShare(opts.estimator, opts.windowMaxBelowShare))
{
	opts.validate();
}

std::optional<MetricScale::Rescale> MetricScale::update(sfm::SparseMap& map)
{
	if (map.keyframes().empty()) return std::nullopt;
	const sfm::KeyFrameId newest = map.keyframes().rbegin()->first;
	const sfm::KeyFrameId every = metric() ? static_cast<sfm::KeyFrameId>(m_opts.reestimateEvery) : 1;
	if (m_lastEstimateAt && newest < *m_lastEstimateAt + every) return std::nullopt;
	if (static_cast<int>(map.numKeyFrames()) < m_opts.estimator.minKeyframes) return std::nullopt;
	m_lastEstimateAt = newest;
	const auto window = estimateWindow(map, metric() ? m_opts.windowPathLength : 0.0);
	bool wholeMap = window.size() == map.numKeyFrames();
	std::size_t pointsSearched = 0;
	auto r = estimateOver(map, window, wholeMap ? m_estimator : m_windowEstimator, &pointsSearched);
	if (!r.ok && wholeMap && metric() && r.failure == sfm::CameraHeightScaleFailure::FloorNotClear)
	{
		// A metric map whose path is still shorter than the window: its floor with the stray
		// points under it that the newest stretch's search tolerates. That generous bound lets
		// planes of stray points through, so the retry may only correct a drift: a larger change
		// is left to the strict search, which can still undo a wrong first estimate.
		auto generous = estimateOver(map, window, m_windowEstimator);
		if (generous.ok && m_opts.windowMaxChange > 0 && std::abs(generous.scale - 1) > m_opts.windowMaxChange)
			r.message = "with window_max_below_share x" + std::to_string(generous.scale) + " exceeds window_max_change = " +
						std::to_string(m_opts.windowMaxChange) + " (" + r.message + ")";
		else if (generous.ok)
		{
			generous.message = "with window_max_below_share (" + r.message + "): " + generous.message;
			r = std::move(generous);
		}
	}
	bool refusedByBound = false, refusedShrink = false;
	if (r.ok && !wholeMap && m_opts.windowMaxChange > 0 && std::abs(r.scale - 1) > m_opts.windowMaxChange)
	{
		// Too large a change for a drift. Unless the whole map says the same (its scale was off
		// before the stretch too: a first estimate that took another plane for the floor), it
		// comes from a plane above the floor and is refused; a shrink that persists over
		// consecutive estimates is a drift (windowPersistentShrink).
		const auto whole = estimateOver(map, estimateWindow(map, 0.0), m_estimator);
		if (whole.ok && std::abs(whole.scale - 1) > m_opts.windowMaxChange &&
			std::abs(std::log(whole.scale / r.scale)) < m_opts.windowMaxChange)
		{
			r = whole;
			r.message = "the whole map agrees with the newest stretch's x" + std::to_string(r.scale) + "; " + r.message;
			wholeMap = true;
		}
		else if (persistentShrink(r.scale))
		{
			r.message = "x" + std::to_string(r.scale) + " along the newest stretch, refused " + std::to_string(m_refusedShrinks.size()) +
						" times in a row before within window_max_change / 2 (the floor lies farther below than camera_height: the map grew), and the whole map " +
						(whole.ok ? "says x" + std::to_string(whole.scale) : "gives no estimate") + "; " + r.message;
		}
		else
		{
			refusedByBound = true;
			refusedShrink = r.scale < 1;
			if (refusedShrink) m_refusedShrinks.push_back(r.scale);
			r.ok = false;
			r.message = "refused: a change of x" + std::to_string(r.scale) + " along the newest stretch exceeds window_max_change = " +
						std::to_string(m_opts.windowMaxChange) + " and the whole map " +
						(whole.ok ? "says x" + std::to_string(whole.scale) : "gives no estimate") +
						(r.scale < 1 ? " (" + std::to_string(m_refusedShrinks.size()) + " in a row)" : " (a plane above the floor?)") + "; " + r.message;
		}
	}
	// A failed estimate says nothing about the drift; any other outcome ends a run of refusals.
	if (r.ok || (refusedByBound && !refusedShrink)) m_refusedShrinks.clear();

	return conclude(map, r, window, wholeMap, "keyframe " + std::to_string(newest) + ", " + std::to_string(window.size()) + " keyframes, " + std::to_string(pointsSearched) + " points: ");
}

}  // namespace keygrid::slam
