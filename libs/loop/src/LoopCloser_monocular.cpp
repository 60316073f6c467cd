/** LoopCloser's monocular path (LoopClosingOptions::monocular): verification of a loop candidate
 * as a similarity between the map points of both keyframes, and its correction by a Sim(3) pose
 * graph. Detection, plausibility, map merging and landmark fusion are LoopCloser.cpp's. */
#include "LoopCorrection.h"
#include "LoopVerification.h"

#include <keygrid/loop/DirectIndexMatcher.h>
#include <keygrid/loop/LoopCloser.h>
#include <keygrid/loop/Sim3MapCorrection.h>
#include <keygrid/sfm/Matcher.h>

#include <set>

namespace keygrid::loop
{
namespace
{
/** Depth of the vocabulary nodes whose features are compared when matching the two keyframes
 * (1 = children of the root): the shipped vocabulary has 4 levels of 10 branches, so level 2
 * groups about 1 / 100 of the features, as ORB-SLAM's 4 levels up from the leaves of 6. */
constexpr int kDirectIndexLevel = 2;
/** Projection check: the loop keyframe and this many of its best covisibles lend their
 * landmarks (ORB-SLAM takes the loop keyframe's covisible group). */
constexpr std::size_t kProjectionGroupNeighbours = 10;
/** Projection check: search radius around the predicted position, times the pyramid scale of
 * the predicted level [px] (ORB-SLAM's 10 for loop landmarks) */
constexpr float kProjectionRadiusPx = 10.0f;

using KeyFrameSims = std::map<sfm::KeyFrameId, Sim3>;

/** The matched keypoints of keyframes a and b that both carry a landmark, as Sim3 matches:
 * each landmark in its keyframe's camera frame. */
std::vector<Sim3Match> landmarkMatches(
	const sfm::SparseMap& map, const sfm::KeyFrame& a, const sfm::KeyFrame& b, const std::vector<DescriptorMatch>& matches)
{
	const Eigen::Isometry3d T_a_world = toIsometry(a.T_world_cam).inverse(), T_b_world = toIsometry(b.T_world_cam).inverse();
	auto sigma = [](const sfm::FrameFeatures& f, int i)
	{ return f.levelScale.empty() ? 1.0 : f.levelScale[static_cast<std::size_t>(f.keypoints[static_cast<std::size_t>(i)].octave)]; };
	std::vector<Sim3Match> out;
	for (const auto& m : matches)
	{
		const auto la = a.landmarks[static_cast<std::size_t>(m.a)], lb = b.landmarks[static_cast<std::size_t>(m.b)];
		if (la == sfm::kNoLandmark || lb == sfm::kNoLandmark || !map.hasLandmark(la) || !map.hasLandmark(lb)) continue;
		Sim3Match s;
		s.p_a = T_a_world * map.landmark(la).p_world;
		s.p_b = T_b_world * map.landmark(lb).p_world;
		const auto& ua = a.features.undistorted[static_cast<std::size_t>(m.a)];
		const auto& ub = b.features.undistorted[static_cast<std::size_t>(m.b)];
		s.uv_a = Eigen::Vector2d(ua.x, ua.y);
		s.uv_b = Eigen::Vector2d(ub.x, ub.y);
		s.sigma_a = sigma(a.features, m.a);
		s.sigma_b = sigma(b.features, m.b);
		out.push_back(s);
	}
	return out;
}
}  // namespace

bool LoopCloser::verifySim3(sfm::KeyFrameId cur, sfm::KeyFrameId cand, const sfm::PinholeIntrinsics& K, Sim3& S_cand_cur, LoopQueryRecord& rec)
{
	// Without depth only the landmarks give 3D points: ORB-SLAM's Sim3Solver on the map points
	// of the matched keypoints (matched under the vocabulary's nodes, DirectIndexMatcher.h).
	const auto& a = m_map.keyframe(cand);
	const auto& b = m_map.keyframe(cur);
	FeatureVector fa, fb;
	m_vocab.transform(a.features.descriptors, fa, kDirectIndexLevel);
	m_vocab.transform(b.features.descriptors, fb, kDirectIndexLevel);
	DirectIndexMatchOptions mo;
	if (!a.features.isBinary()) mo.maxDistance = m_matcher.maxDistanceSift;
	const auto matches = landmarkMatches(m_map, a, b, matchByDirectIndex(a.features.descriptors, fa, b.features.descriptors, fb, mo));
	rec.matches = static_cast<int>(matches.size());
	Sim3RansacOptions ransac = m_opts.sim3;
	ransac.fixScale = m_metricUnits;
	const auto r = detail::verifiedByRansac(rec, ransac.minInliers, [&] { return estimateSim3Ransac(matches, K, ransac); });
	if (!r) return false;
	// A few matches can agree by chance; a true loop puts the whole place right: the loop
	// side's landmarks must land on the current keyframe's keypoints.
	rec.projectedMatches = countProjectedMatches(cur, cand, r->S_a_b, K);
	if (rec.projectedMatches < m_opts.sim3MinMatches)
	{
		rec.outcome = LoopQueryOutcome::ProjectionFailed;
		return false;
	}
	S_cand_cur = r->S_a_b;
	return true;
}

int LoopCloser::countProjectedMatches(sfm::KeyFrameId cur, sfm::KeyFrameId cand, const Sim3& S_cand_cur, const sfm::PinholeIntrinsics& K) const
{
	// A point x of the loop keyframe's frame lies at S_cur_cand x = s R x + t in the current
	// camera, which projects where R x + t / s does: the current camera as a rigid pose in
	// the loop side's units, so that the landmarks' distance ranges (in those units) apply.
	const Sim3 S_cur_cand = S_cand_cur.inverse();
	Eigen::Isometry3d T_cur_cand = Eigen::Isometry3d::Identity();
	T_cur_cand.linear() = S_cur_cand.q.toRotationMatrix();
	T_cur_cand.translation() = S_cur_cand.t / S_cur_cand.s;
	const Eigen::Isometry3d T_cur_world = T_cur_cand * toIsometry(m_map.keyframe(cand).T_world_cam).inverse();
	const mrpt::poses::CPose3D T_cam_world = toCPose3D(T_cur_world);
	const Eigen::Vector3d center = T_cur_world.inverse().translation();

	std::set<sfm::LandmarkId> loopSide;
	std::vector<sfm::KeyFrameId> group = {cand};
	for (const auto n : m_map.bestCovisibles(cand, kProjectionGroupNeighbours)) group.push_back(n);
	for (const auto id : group)
		for (const auto l : m_map.keyframe(id).landmarks)
			if (l != sfm::kNoLandmark && m_map.hasLandmark(l)) loopSide.insert(l);
	const auto& f = m_map.keyframe(cur).features;
	std::vector<sfm::ProjectedLandmark> projected;
	for (const auto l : loopSide)
	{
		sfm::ProjectedLandmark p;
		if (sfm::projectLandmark(m_map.landmark(l), T_cam_world, center, K, f, m_matcher, p)) projected.push_back(p);
	}
	std::vector<sfm::LandmarkId> matches(f.keypoints.size(), sfm::kNoLandmark);
	return sfm::searchByProjection(f, projected, kProjectionRadiusPx, m_matcher, matches);
}

LoopClosureEvent LoopCloser::correctSim3(sfm::KeyFrameId cur, sfm::KeyFrameId cand, const Sim3& S_cand_cur, const sfm::PinholeIntrinsics& K)
{
	// As correct(), with similarities: every keyframe a vertex of unit scale, odometry and
	// covisibility edges keeping the current relative poses at unit relative scale, the loop
	// edge the verified similarity. The first keyframe is fixed, scale included: the corrected
	// map keeps its units (those of the map start, or the metres of slam::MetricScale), and the
	// scale drift is spread over the keyframes of the loop. A merge first moves the current
	// map by the similarity that makes the loop measurement hold. In a metric map (setMetricUnits)
	// the loop's similarity has unit scale and every keyframe keeps its scale.
	const std::uint32_t curMap = m_map.keyframe(cur).mapId, loopMap = m_map.keyframe(cand).mapId;
	const bool merge = curMap != loopMap;
	const KeyFrameSims oldS = keyFrameSims(m_map);
	const Sim3 align = merge ? oldS.at(cand) * S_cand_cur * oldS.at(cur).inverse() : Sim3{};
	Sim3PoseGraph g = detail::loopCorrectionGraph<Sim3PoseGraph>(m_map, oldS, cur, cand, S_cand_cur, align, m_opts.covisibilityEdgeMinWeight);
	g.setScalesFixed(m_metricUnits);
	PoseGraphOptions o = m_opts.poseGraph;
	o.loopLossScale = Sim3PoseGraph::defaultOptions().loopLossScale;  // 7 DOF instead of 6
	const auto summary = g.optimize(o);

	LoopClosureEvent ev;
	ev.keyframe = cur;
	ev.loopKeyFrame = cand;
	ev.T_loop_cur = toCPose3D(S_cand_cur.rigid());
	if (!summary.usable) return ev;
	ev.mergedMap = merge;
	KeyFrameSims newS;
	for (const auto& c : summary.corrections)
	{
		newS[c.id] = c.S_world_kf_new;
		if (merge && m_map.keyframe(c.id).mapId == curMap) m_map.keyframe(c.id).mapId = loopMap;
		ev.newScales[c.id] = c.S_world_kf_new.s / oldS.at(c.id).s;
	}
	// The cameras' centres and orientations; their scales go into their landmarks.
	applySim3Corrections(m_map, oldS, newS);
	for (const auto& [id, S] : newS) ev.newPoses[id] = m_map.keyframe(id).T_world_cam;
	ev.correctionMetres = (newS.at(cur).t - oldS.at(cur).t).norm();
	ev.scaleCorrection = newS.at(cur).s / oldS.at(cur).s;
	detail::joinLoopSides(m_map, m_mapper, cur, cand, K);
	return ev;
}

}  // namespace keygrid::loop
