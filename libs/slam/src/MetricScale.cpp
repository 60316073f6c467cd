#include <keygrid/slam/MetricScale.h>
#include <mrpt/config/CConfigFileBase.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace keygrid::slam
{
core::OptionFields MetricScaleOptions::fields()
{
	core::OptionFields f = estimator.fields();
	f.add("min_point_parallax_deg", minPointParallaxDeg, "map points seen under rays less far apart are left out of the floor search [deg]; 0 = all", core::OptionRule::fromBelow(0, 90));
	f.add("window_path_length", windowPathLength, "once metric, the floor is searched along this much of the newest path [m]; 0 = whole map", core::OptionRule::atLeast(0));
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
/** Cosine of the largest angle between the rays of the first observing keyframe and each
 * other one towards the landmark (1: seen from one place only). */
double largestParallaxCos(const sfm::SparseMap& map, const sfm::Landmark& lm)
{
	double minCos = 1.0;
	std::optional<Eigen::Vector3d> first;
	for (const auto& [kf, idx] : lm.observations)
	{
		if (!map.hasKeyFrame(kf)) continue;
		const auto& t = map.keyframe(kf).T_world_cam;
		const Eigen::Vector3d ray = (lm.p_world - Eigen::Vector3d(t.x(), t.y(), t.z())).normalized();
		if (!first) first = ray;
		else
			minCos = std::min(minCos, first->dot(ray));
	}
	return minCos;
}

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
		const auto& t = it->second.T_world_cam;
		const Eigen::Vector3d c(t.x(), t.y(), t.z());
		if (next) travelled += (*next - c).norm();
		if (pathLength > 0 && travelled > pathLength) break;
		ids.push_back(it->first);
		next = c;
	}
	std::reverse(ids.begin(), ids.end());
	return ids;
}

/** Whether a keyframe of the (sorted) window observes the landmark. */
bool observedFrom(const sfm::Landmark& lm, const std::vector<sfm::KeyFrameId>& window)
{
	for (const auto& obs : lm.observations)
		if (std::binary_search(window.begin(), window.end(), obs.first)) return true;
	return false;
}
}  // namespace

MetricScale::MetricScale(const MetricScaleOptions& opts) : m_opts(opts), m_estimator(opts.estimator) { opts.validate(); }

std::optional<double> MetricScale::update(sfm::SparseMap& map)
{
	if (map.keyframes().empty()) return std::nullopt;
	const sfm::KeyFrameId newest = map.keyframes().rbegin()->first;
	const sfm::KeyFrameId every = metric() ? static_cast<sfm::KeyFrameId>(m_opts.reestimateEvery) : 1;
	if (m_lastEstimateAt && newest < *m_lastEstimateAt + every) return std::nullopt;
	if (static_cast<int>(map.numKeyFrames()) < m_opts.estimator.minKeyframes) return std::nullopt;
	m_lastEstimateAt = newest;
	const auto window = estimateWindow(map, metric() ? m_opts.windowPathLength : 0.0);
	std::vector<mrpt::poses::CPose3D> poses;
	poses.reserve(window.size());
	for (const sfm::KeyFrameId id : window) poses.push_back(map.keyframe(id).T_world_cam);
	// The well-triangulated points first; when they give no estimate (too few yet, or no clear
	// floor among them), every point.
	std::vector<Eigen::Vector3d> points, all;
	const double minCos = std::cos(m_opts.minPointParallaxDeg * M_PI / 180.0);
	const bool wholeMap = window.size() == map.numKeyFrames();
	for (const auto& [id, lm] : map.landmarks())
	{
		if (!wholeMap && !observedFrom(lm, window)) continue;
		all.push_back(lm.p_world);
		if (!(largestParallaxCos(map, lm) > minCos)) points.push_back(lm.p_world);
	}
	auto r = m_estimator.estimate(poses, points);
	if (!r.ok && points.size() < all.size()) r = m_estimator.estimate(poses, all);
	m_stats.estimates++;
	m_stats.lastMessage = r.message;
	if (m_log.size() < kMaxLogLines)
		m_log.push_back(
			"keyframe " + std::to_string(newest) + ", " + std::to_string(window.size()) + " keyframes, " + std::to_string(all.size()) +
			" points: " + (r.ok ? "x" + std::to_string(r.scale) + ", " : "") + r.message);
	if (!r.ok) return std::nullopt;
	map.rescale(r.scale);
	// The plane was found in the map before the rescale: its offset scales with the map.
	m_floorPlane = FloorPlane{r.floorNormal, r.floorOffset * r.scale};
	m_stats.applied++;
	m_stats.totalFactor *= r.scale;
	m_stats.lastFactor = r.scale;
	return r.scale;
}

}  // namespace keygrid::slam
