/** \file HocFrontend.cpp
 * HOC selection, per-frame update and pruning in the tracker (rule: HocFrontend.h).
 */
#include <keygrid/sfm/HocFrontend.h>

#include <algorithm>
#include <cmath>
#include <set>

namespace keygrid::sfm
{
HocFrontend::HocFrontend(const maps::HocOptions& opts) : m_opts(opts), m_geom(opts.radii, opts.subdivisions)
{
	m_opts.validate();
}

void HocFrontend::seed(Landmark& lm, const SparseMap& map) const
{
	if (lm.hoc.touched()) return;
	for (const auto& [kf, kp] : lm.observations)
	{
		if (!map.hasKeyFrame(kf)) continue;
		const int b = m_geom.bin(lm.p_world, map.keyframe(kf).cameraCenter());
		if (b >= 0) lm.hoc.add(b, m_opts.initialCount, m_opts.countLimit, m_geom.numBins());
	}
}

bool HocFrontend::usable(Landmark& lm, const SparseMap& map, const Eigen::Vector3d& c) const
{
	seed(lm, map);
	const int b = m_geom.bin(lm.p_world, c);
	return b < 0 || m_opts.weight(lm.hoc.count(b)) > m_opts.selectThreshold;
}

bool HocFrontend::hasDepth(const cv::Mat& depth, float u, float v)
{
	const int x = static_cast<int>(std::lround(u)), y = static_cast<int>(std::lround(v));
	if (depth.empty() || x < 0 || y < 0 || x >= depth.cols || y >= depth.rows) return false;
	const float d = depth.at<float>(y, x);
	return std::isfinite(d) && d > 0;
}

bool HocFrontend::keypointInWindow(const FrameFeatures& f, const ProjectedLandmark& p, float radius)
{
	const float r = radius * static_cast<float>(f.levelScale.empty() ? 1.0 : f.levelScale[p.predictedLevel]);
	return !f.featuresInArea(p.u, p.v, r, std::max(0, p.predictedLevel - 1), p.predictedLevel + 1).empty();
}

bool HocFrontend::occluded(const cv::Mat& depth, float u, float v, float predicted) const
{
	if (!hasDepth(depth, u, v)) return false;
	const float d = depth.at<float>(static_cast<int>(std::lround(v)), static_cast<int>(std::lround(u)));
	return d < predicted - (m_opts.occlusionToleranceAbs + m_opts.occlusionToleranceRel * predicted);
}

HocUpdateStats HocFrontend::update(
	SparseMap& map, const FrameFeatures& f, const std::vector<LandmarkId>& matched,
	const std::vector<ProjectedLandmark>& visible, const std::vector<ProjectedLandmark>& excluded,
	const cv::Mat& depth, const Eigen::Vector3d& c, float searchRadius, const MatcherOptions& matcherOpts) const
{
	HocUpdateStats st;
	const int nb = m_geom.numBins();
	auto bump = [&](Landmark& lm, int delta) {
		const int b = m_geom.bin(lm.p_world, c);
		if (b < 0) return;
		seed(lm, map);
		lm.hoc.add(b, delta, m_opts.countLimit, nb);
		(delta > 0 ? st.incremented : st.decremented)++;
	};
	std::set<LandmarkId> done;
	for (LandmarkId id : matched)
		if (id != kNoLandmark && map.hasLandmark(id) && done.insert(id).second) bump(map.landmark(id), +1);

	// Excluded landmarks: a guided search among the keypoints left free. Matches found here
	// only feed the histogram, never the pose.
	std::vector<LandmarkId> again(matched);
	searchByProjection(f, excluded, searchRadius, matcherOpts, again);
	std::set<LandmarkId> recovered;
	for (std::size_t i = 0; i < again.size(); i++)
		if (again[i] != kNoLandmark && again[i] != matched[i]) recovered.insert(again[i]);

	std::vector<LandmarkId> decremented;
	auto miss = [&](const ProjectedLandmark& p) {
		if (!done.insert(p.id).second || !map.hasLandmark(p.id)) return;
		auto& lm = map.landmark(p.id);
		seed(lm, map);
		if (recovered.count(p.id))
		{
			bump(lm, +1);
			st.recovered++;
			return;
		}
		// No depth reading where an in-range surface is predicted counts as not occluded:
		// an occluder would be closer, hence measured.
		if (depth.empty() || p.depth < m_opts.visibleDepthMin || p.depth > m_opts.visibleDepthMax) return;
		if (occluded(depth, p.u, p.v, p.depth))
		{
			st.occluded++;
			return;
		}
		// "Should have been seen" also needs the detector to have fired where the point was
		// searched for. A static point is matched in a frame with probability q (ORB: about
		// 0.5); with +1 per match and -1 per miss its n drifts by q - (1 - q) = 2q - 1 per
		// frame, i.e. down when q < 1/2, although nothing changed. A miss with no keypoint in
		// the window is about as likely for a present point as for a vanished one (likelihood
		// ratio ~1: no evidence), so it is not counted; a miss with keypoints there that none
		// matched is counted.
		if (m_opts.decrementNeedsKeypoint && !keypointInWindow(f, p, searchRadius))
		{
			st.undetected++;
			return;
		}
		bump(lm, -1);
		decremented.push_back(p.id);
	};
	for (const auto& p : visible) miss(p);
	for (const auto& p : excluded) miss(p);

	// Pruning: only a decrement can take a landmark's maximum below the threshold.
	for (LandmarkId id : decremented)
		if (map.hasLandmark(id) && m_opts.weight(map.landmark(id).hoc.maxCount()) < m_opts.pruneThreshold)
		{
			map.eraseLandmark(id);
			st.pruned++;
		}
	return st;
}

}  // namespace keygrid::sfm
