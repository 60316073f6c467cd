/** \file HocFrontend.cpp
 * HOC selection, per-frame update and pruning in the tracker (rule: HocFrontend.h).
 */
#include <keygrid/sfm/HocFrontend.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

namespace keygrid::sfm
{
HocFrontend::HocFrontend(const maps::HocOptions& opts) : m_opts(opts), m_geom(opts.radii, opts.subdivisions)
{
	m_opts.validate();
	// The sigmoid is evaluated for every landmark in view, twice per frame: tabulated.
	for (int n = -m_opts.countLimit; n <= m_opts.countLimit; n++) m_weights.push_back(m_opts.weight(n));
}

double HocFrontend::weight(int n) const
{
	const int i = n + m_opts.countLimit;
	return i >= 0 && i < static_cast<int>(m_weights.size()) ? m_weights[static_cast<std::size_t>(i)] : m_opts.weight(n);
}

void HocFrontend::seed(Landmark& lm, const SparseMap& map) const
{
	if (lm.hoc.touched()) return;
	// Only the creating keyframe observed the point at frame time. Observations that local
	// mapping adds later in older keyframes (fusion, triangulation) are associations made in
	// hindsight: a walker that passes the same spot twice is "fused" into the keyframe of its
	// first pass. Counting them would let unconfirmed points pass the selection.
	const KeyFrameId kf = lm.firstKeyFrame;
	if (!map.hasKeyFrame(kf)) return;  // culled before first use: n = 0, unconfirmed
	const int b = m_geom.bin(lm.p_world, map.keyframe(kf).cameraCenter());
	if (b >= 0) lm.hoc.add(b, m_opts.initialCount, m_opts.countLimit, m_geom.numBins());
}

void HocFrontend::confirmInitialMap(SparseMap& map, KeyFrameId kf) const
{
	if (!map.hasKeyFrame(kf)) return;
	const Eigen::Vector3d c = map.keyframe(kf).cameraCenter();
	for (LandmarkId id : map.keyframe(kf).landmarks)
	{
		if (id == kNoLandmark || !map.hasLandmark(id)) continue;
		auto& lm = map.landmark(id);
		seed(lm, map);
		const int b = m_geom.bin(lm.p_world, c);
		if (b >= 0) lm.hoc.add(b, 1, m_opts.countLimit, m_geom.numBins());
	}
}

bool HocFrontend::usable(Landmark& lm, const SparseMap& map, const Eigen::Vector3d& c, bool fallback) const
{
	seed(lm, map);
	const int b = m_geom.bin(lm.p_world, c);
	const double threshold = fallback ? std::min(m_opts.selectThreshold, m_opts.weight(0)) : m_opts.selectThreshold;
	return b < 0 || weight(lm.hoc.count(b)) > threshold;
}

bool HocFrontend::fitsPose(const FrameFeatures& f, int kp, const ProjectedLandmark& p) const
{
	// The pose refinement's inlier test (PoseOptimizer.h): squared reprojection error in units
	// of the keypoint's level scale, plus the virtual-disparity residual bf/z when both depths
	// are known, against the 95 % chi-square bound (2 or 3 DOF). The search window alone lets
	// a walker's point count as seen: it accepts up to radius * scale pixels of motion.
	const double s = f.levelScale[f.keypoints[kp].octave];
	const double du = (f.undistorted[kp].x - p.u) / s, dv = (f.undistorted[kp].y - p.v) / s;
	double e2 = du * du + dv * dv;
	const bool rgbd = f.depth[kp] > 0 && p.depth > 0 && f.depth[kp] < m_gate.maxDepthForRgbd;
	if (rgbd)
	{
		const double dr = (m_gate.bf / f.depth[kp] - m_gate.bf / p.depth) / m_gate.disparitySigma;
		e2 += dr * dr;
	}
	return e2 <= (rgbd ? m_gate.chi2Rgbd : m_gate.chi2Mono);
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
	return f.anyFeatureInArea(p.u, p.v, r, std::max(0, p.predictedLevel - 1), p.predictedLevel + 1);
}

bool HocFrontend::occluded(const cv::Mat& depth, float u, float v, float predicted) const
{
	if (!hasDepth(depth, u, v)) return false;
	const float d = depth.at<float>(static_cast<int>(std::lround(v)), static_cast<int>(std::lround(u)));
	return d < predicted - (m_opts.occlusionToleranceAbs + m_opts.occlusionToleranceRel * predicted);
}

bool HocFrontend::seenThrough(const cv::Mat& depth, float u, float v, float predicted) const
{
	// A 3 x 3 pattern of samples 3 px apart: a point on a depth edge, whose projection lands
	// on the far side after a pixel of pose or depth error, has near samples too; a point
	// whose whole surroundings read farther away is gone. Holes count as "not seen through"
	// (Kinect holes cluster at edges and on dark or shiny surfaces).
	constexpr int kStep = 3;
	const float tol = static_cast<float>(m_opts.occlusionToleranceAbs + m_opts.occlusionToleranceRel * predicted);
	for (int dy = -kStep; dy <= kStep; dy += kStep)
		for (int dx = -kStep; dx <= kStep; dx += kStep)
		{
			if (!hasDepth(depth, u + dx, v + dy)) return false;
			const float d = depth.at<float>(static_cast<int>(std::lround(v + dy)), static_cast<int>(std::lround(u + dx)));
			if (!(d > predicted + tol)) return false;
		}
	return true;
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
	// Membership tests only (nothing iterates these), so hash sets; results do not depend on it.
	std::unordered_set<LandmarkId> done;
	done.reserve(2 * (matched.size() + visible.size() + excluded.size()));
	// One map lookup per landmark (findLandmark): the map is a std::map, each lookup a tree walk.
	for (LandmarkId id : matched)
		if (id != kNoLandmark && done.insert(id).second)
			if (Landmark* lm = map.findLandmark(id)) bump(*lm, +1);

	// Excluded landmarks: a guided search among the keypoints left free. Matches found here
	// only feed the histogram, never the pose.
	std::vector<LandmarkId> again(matched);
	searchByProjection(f, excluded, searchRadius, matcherOpts, again);
	std::unordered_set<LandmarkId> recovered;
	std::unordered_map<LandmarkId, const ProjectedLandmark*> proj;
	proj.reserve(2 * excluded.size());
	for (const auto& p : excluded) proj[p.id] = &p;
	for (std::size_t i = 0; i < again.size(); i++)
		if (again[i] != kNoLandmark && again[i] != matched[i] && fitsPose(f, static_cast<int>(i), *proj.at(again[i])))
			recovered.insert(again[i]);

	std::vector<LandmarkId> decremented;
	auto miss = [&](const ProjectedLandmark& p) {
		Landmark* found = done.insert(p.id).second ? map.findLandmark(p.id) : nullptr;
		if (!found) return;
		auto& lm = *found;
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
		// matched is counted. So is a miss where the depth image reads a surface behind the point
		// all around its projection (seenThrough): the point moved or vanished, and a textureless
		// background would otherwise never let it be pruned.
		if (m_opts.decrementNeedsKeypoint && !keypointInWindow(f, p, searchRadius))
		{
			if (!seenThrough(depth, p.u, p.v, p.depth))
			{
				st.undetected++;
				return;
			}
			st.seenThrough++;
		}
		bump(lm, -1);
		decremented.push_back(p.id);
	};
	for (const auto& p : visible) miss(p);
	for (const auto& p : excluded) miss(p);

	// Pruning: only a decrement can take a landmark's maximum below the threshold.
	for (LandmarkId id : decremented)
		if (const Landmark* lm = map.findLandmark(id); lm && weight(lm->hoc.maxCount()) < m_opts.pruneThreshold)
		{
			map.eraseLandmark(id);
			st.pruned++;
		}
	return st;
}

}  // namespace keygrid::sfm
