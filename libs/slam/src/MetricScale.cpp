#include <keygrid/slam/MetricScale.h>
#include <mrpt/config/CConfigFileBase.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

namespace keygrid::slam
{
core::OptionFields MetricScaleOptions::fields()
{
	core::OptionFields f = estimator.fields();
	f.add("min_point_parallax_deg", minPointParallaxDeg, "map points seen under rays less far apart are left out of the floor search [deg]; 0 = all", core::OptionRule::fromBelow(0, 90));
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
	std::vector<mrpt::poses::CPose3D> poses;
	poses.reserve(map.numKeyFrames());
	for (const auto& [id, kf] : map.keyframes()) poses.push_back(kf.T_world_cam);
	// The well-triangulated points first; when they give no estimate (too few yet, or no clear
	// floor among them), every point.
	std::vector<Eigen::Vector3d> points, all;
	points.reserve(map.numLandmarks());
	all.reserve(map.numLandmarks());
	const double minCos = std::cos(m_opts.minPointParallaxDeg * M_PI / 180.0);
	for (const auto& [id, lm] : map.landmarks())
	{
		all.push_back(lm.p_world);
		if (!(largestParallaxCos(map, lm) > minCos)) points.push_back(lm.p_world);
	}
	auto r = m_estimator.estimate(poses, points);
	if (!r.ok && points.size() < all.size()) r = m_estimator.estimate(poses, all);
	m_stats.estimates++;
	m_stats.lastMessage = r.message;
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
