#pragma once
/** \file LoopCorrection.h
 * The steps of a loop correction shared by LoopCloser's rigid (RGB-D) and similarity
 * (monocular) paths, written once for both pose types: Eigen::Isometry3d with PoseGraph and
 * Sim3 with Sim3PoseGraph. Internal to libs/loop.
 */
#include <keygrid/loop/PoseGraph.h>
#include <keygrid/loop/Sim3PoseGraph.h>
#include <keygrid/sfm/LocalMapper.h>
#include <keygrid/sfm/SparseMap.h>

#include <map>
#include <type_traits>
#include <utility>
#include <vector>

namespace keygrid::loop::detail
{
/** Each side of a loop (seen-through test, landmark fusion): the keyframe and this many of its
 * best covisibles. */
constexpr std::size_t kLoopSideNeighbours = 5;

/** The pose graph of a loop correction (see LoopCloser::correct): a vertex per keyframe, the
 * keyframes of the current map moved first by `align`; odometry edges between consecutive
 * keyframes of one map and covisibility edges between strongly covisible ones, all keeping
 * their current relative poses (unit relative scale for Sim3); the loop edge with its
 * measurement; the gauge fixed. */
template <class Graph, class Pose>
Graph loopCorrectionGraph(
	const sfm::SparseMap& map, const std::map<sfm::KeyFrameId, Pose>& oldPoses, sfm::KeyFrameId cur, sfm::KeyFrameId cand,
	const Pose& measured_cand_cur, const Pose& align, int covisibilityEdgeMinWeight)
{
	using Edge = typename std::decay_t<decltype(std::declval<Graph>().edges())>::value_type;
	using Information = decltype(Edge{}.information);
	const std::uint32_t curMap = map.keyframe(cur).mapId;
	const bool merge = curMap != map.keyframe(cand).mapId;
	Graph g;
	for (const auto& [id, kf] : map.keyframes()) g.addVertex(id, kf.mapId == curMap ? Pose(align * oldPoses.at(id)) : oldPoses.at(id));
	auto rel = [&](sfm::KeyFrameId a, sfm::KeyFrameId b) { return Pose(g.pose(a).inverse() * g.pose(b)); };
	std::map<std::uint32_t, sfm::KeyFrameId> prevOfMap;
	for (const auto& [id, kf] : map.keyframes())
	{
		const auto p = prevOfMap.find(kf.mapId);
		const bool hasPrev = p != prevOfMap.end();
		const sfm::KeyFrameId prev = hasPrev ? p->second : 0;
		if (hasPrev) g.addEdge({prev, id, rel(prev, id), Information::Identity(), EdgeKind::Odometry});
		for (const auto& [other, w] : kf.covisibility)
			if (other < id && w >= covisibilityEdgeMinWeight && (!hasPrev || other != prev))
				g.addEdge({other, id, rel(other, id), Information::Identity(), EdgeKind::Covisibility});
		prevOfMap[kf.mapId] = id;
	}
	g.addEdge({cand, cur, measured_cand_cur, Information::Identity(), EdgeKind::Loop});
	// Gauge: the first keyframe defines the world frame (and, for Sim3, the map's units); the
	// loop only bends the rest onto it. A loop inside a map not merged yet keeps that map's
	// first keyframe in place.
	g.setFixed(map.keyframes().begin()->first);
	if (!merge && map.keyframes().begin()->second.mapId != curMap)
		for (const auto& [id, kf] : map.keyframes())
			if (kf.mapId == curMap)
			{
				g.setFixed(id);
				break;
			}
	return g;
}

/** Landmarks follow the keyframe that created them (or their first observer) from its pose in
 * oldPoses to its pose in newPoses (movePointWithKeyFrame: for Sim3 the scale correction
 * included); landmarks of keyframes not corrected stay. */
template <class Pose>
void moveLandmarksWithKeyFrames(
	sfm::SparseMap& map, const std::map<sfm::KeyFrameId, Pose>& oldPoses, const std::map<sfm::KeyFrameId, Pose>& newPoses)
{
	std::vector<std::pair<sfm::LandmarkId, Eigen::Vector3d>> moved;
	for (const auto& [id, lm] : map.landmarks())
	{
		sfm::KeyFrameId ref = lm.firstKeyFrame;
		if (!newPoses.count(ref)) ref = lm.observations.begin()->first;
		if (!newPoses.count(ref)) continue;
		moved.emplace_back(id, movePointWithKeyFrame(lm.p_world, oldPoses.at(ref), newPoses.at(ref)));
	}
	for (const auto& [id, p] : moved) map.landmark(id).p_world = p;
}

/** Joins both sides of a closed loop: the landmarks of the loop keyframe's neighbourhood are
 * fused into the current keyframe's neighbourhood, whose covisibility is then updated. */
void joinLoopSides(sfm::SparseMap& map, sfm::LocalMapper& mapper, sfm::KeyFrameId cur, sfm::KeyFrameId cand, const sfm::PinholeIntrinsics& K);

}  // namespace keygrid::loop::detail
