#include <keygrid/slam/MetricScale.h>
#include <mrpt/config/CConfigFileBase.h>

#include <vector>

namespace keygrid::slam
{
core::OptionFields MetricScaleOptions::fields()
{
	core::OptionFields f = estimator.fields();
	f.add("reestimate_every", reestimateEvery, "after the first estimate, estimate and rescale again every this many keyframes", core::OptionRule::positive());
	return f;
}

void MetricScaleOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	fields().read(c, s);
	validate(s);
}

void MetricScaleOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const { core::writeFields(*this, c, s); }

void MetricScaleOptions::validate(const std::string& s) const
{
	core::validateFields(*this, s);
	estimator.validate(s);
}

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
	std::vector<Eigen::Vector3d> points;
	points.reserve(map.numLandmarks());
	for (const auto& [id, lm] : map.landmarks()) points.push_back(lm.p_world);
	const auto r = m_estimator.estimate(poses, points);
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
