#include <keygrid/sfm/LocalMapper.h>
#include <mrpt/config/CConfigFileBase.h>

#include <keygrid/sfm/Triangulation.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>

namespace keygrid::sfm
{
core::OptionFields LocalMapperOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("fuse_neighbours", fuseNeighbours, "neighbour keyframes searched for duplicate landmarks", R::atLeast(0));
	f.add("fuse_radius", fuseRadius, "fusion search radius [px]");
	f.add("fuse_max_distance_orb", fuseMaxDistanceOrb, "fusion descriptor threshold [Hamming bits]");
	f.add("min_found_ratio", minFoundRatio, "new landmarks matched in less than this share of their views are culled");
	f.add("redundant_keyframe_ratio", redundantKeyFrameRatio, "keyframes whose landmarks are this redundant are culled", R::aboveUpTo(0, 1));
	f.add("triangulation_neighbours", triangulationNeighbours, "keyframes searched for triangulated landmarks", R::atLeast(0));
	f.add("min_parallax_deg", minParallaxDeg, "smallest parallax of a triangulated landmark [deg]");
	f.add("local_bundle_adjustment", localBundleAdjustment, "bundle-adjust the covisible window after each keyframe");
	f.append(ba.fields());
	return f;
}

void LocalMapperOptions::validate(const std::string& s) const { core::validateFields(*this, s); }

LocalMapper::LocalMapper(SparseMap& map, const LocalMapperOptions& opts, const MatcherOptions& matcher)
	: m_map(map), m_opts(opts), m_matcher(matcher)
{
}

LocalMappingPass::LocalMappingPass(KeyFrameId kf) : m_kf(kf), m_stageStart(std::chrono::steady_clock::now()) {}

void LocalMappingPass::lap(const char* stage)
{
	const auto now = std::chrono::steady_clock::now();
	m_report.stageSeconds.emplace_back(stage, std::chrono::duration<double>(now - m_stageStart).count());
	m_stageStart = now;
}

void LocalMappingPass::solve()
{
	if (m_ba) m_ba->solve();
}

void LocalMapper::refine(LocalMappingPass& pass, const PinholeIntrinsics& K)
{
	const KeyFrameId kf = pass.m_kf;
	// Landmarks created by this keyframe join the probation list.
	for (LandmarkId l : m_map.keyframe(kf).landmarks)
		if (l != kNoLandmark && m_map.hasLandmark(l) && m_map.landmark(l).firstKeyFrame == kf) m_recent.push_back(l);
	pass.m_report.culledLandmarks = cullRecentLandmarks(kf);
	pass.lap("cull");
	pass.m_refined = m_map.numKeyFrames() > 1;
	if (!pass.m_refined) return;
	pass.m_report.triangulated = triangulateNew(kf, K);
	pass.lap("triangulate");
	fuse(kf, K, pass.m_report);
	m_map.updateCovisibility(kf);
	pass.lap("fuse");
}

LocalMappingReport LocalMapper::process(KeyFrameId kf, const PinholeIntrinsics& K)
{
	LocalMappingPass pass(kf);
	refine(pass, K);
	if (pass.m_refined)
	{
		if (m_opts.localBundleAdjustment)
		{
			pass.m_report.ba = localBundleAdjustment(m_map, kf, K, m_opts.ba);
			pass.lap("ba");
		}
		pass.m_report.culledKeyFrames = cullKeyFrames(kf);
		pass.lap("cull_keyframes");
	}
	return std::move(pass.m_report);
}

LocalMappingPass LocalMapper::prepare(KeyFrameId kf, const PinholeIntrinsics& K)
{
	LocalMappingPass pass(kf);
	refine(pass, K);
	if (pass.m_refined && m_opts.localBundleAdjustment)
	{
		pass.m_ba.emplace(BundleAdjustment::around(m_map, kf, K, m_opts.ba));
		pass.m_correctionsAtBuild = m_map.corrections();
		pass.lap("ba_build");
	}
	return pass;
}

LocalMappingReport LocalMapper::complete(LocalMappingPass pass)
{
	if (pass.m_ba)
	{
		pass.lap("ba_solve");
		// Only the mapper erases keyframes, so the keyframe is still there; a loop correction
		// during the solve would be undone by writing back the old-frame result.
		if (m_map.corrections() == pass.m_correctionsAtBuild) pass.m_report.ba = pass.m_ba->apply(m_map);
		else
			pass.m_report.baDiscarded = true;
		pass.lap("ba_apply");
	}
	if (pass.m_refined)
	{
		pass.m_report.culledKeyFrames = cullKeyFrames(pass.m_kf);
		pass.lap("cull_keyframes");
	}
	return std::move(pass.m_report);
}

int LocalMapper::triangulateNew(KeyFrameId kfId, const PinholeIntrinsics& K)
{
	int created = 0;
	const double cosMaxParallax = std::cos(m_opts.minParallaxDeg * M_PI / 180.0);
	for (KeyFrameId nId : m_map.bestCovisibles(kfId, static_cast<std::size_t>(m_opts.triangulationNeighbours)))
	{
		auto& a = m_map.keyframe(kfId);
		const auto& b = m_map.keyframe(nId);
		// Baseline too short for the scene depth: nothing to gain.
		if ((a.cameraCenter() - b.cameraCenter()).norm() < 0.01) continue;
		// Candidates: keypoints of the new keyframe without a landmark and without valid depth
		// (those with depth already became landmarks or were rejected). Recomputed per
		// neighbour because the previous neighbour's triangulations took some.
		std::vector<int> ia;
		for (std::size_t i = 0; i < a.landmarks.size(); i++)
			if (a.landmarks[i] == kNoLandmark && !(a.features.depth[i] > 0)) ia.push_back(static_cast<int>(i));
		for (const auto& [i, j] : matchSubsetBruteForce(a.features, ia, b.features, m_matcher.maxDistance(a.features.isBinary()), 0.8f))
		{
			if (b.landmarks[j] != kNoLandmark) continue;
			const Eigen::Vector2d ua(a.features.undistorted[i].x, a.features.undistorted[i].y);
			const Eigen::Vector2d ub(b.features.undistorted[j].x, b.features.undistorted[j].y);
			Eigen::Vector3d p;
			if (!triangulateDlt(a.T_world_cam, ua, b.T_world_cam, ub, K, p)) continue;
			if (std::cos(parallaxAngle(a.T_world_cam, b.T_world_cam, p)) > cosMaxParallax) continue;
			// Reprojection in both views within the 2-DOF chi-square bound at their levels.
			bool ok = true;
			for (const KeyFrame* k : {static_cast<const KeyFrame*>(&a), &b})
			{
				const int kp = k == &a ? i : j;
				double x, y, z;
				(-k->T_world_cam).composePoint(p.x(), p.y(), p.z(), x, y, z);
				const double s = k->features.levelScale[k->features.keypoints[kp].octave];
				const double du = K.fx * x / z + K.cx - k->features.undistorted[kp].x;
				const double dv = K.fy * y / z + K.cy - k->features.undistorted[kp].y;
				if ((du * du + dv * dv) / (s * s) > 5.991) ok = false;
			}
			if (!ok) continue;
			const LandmarkId id = m_map.addLandmark(p, kfId, i);
			m_map.addObservation(id, nId, j);
			m_map.updateLandmarkStats(id);
			m_recent.push_back(id);
			++created;
		}
	}
	return created;
}

int LocalMapper::cullRecentLandmarks(KeyFrameId current)
{
	int culled = 0;
	std::deque<LandmarkId> keep;
	for (LandmarkId id : m_recent)
	{
		if (!m_map.hasLandmark(id)) continue;
		const auto& l = m_map.landmark(id);
		const KeyFrameId age = current - l.firstKeyFrame;
		if (l.foundRatio() < m_opts.minFoundRatio || (age >= 2 && l.observations.size() < 2))
		{
			m_map.eraseLandmark(id);
			++culled;
		}
		else if (age < 3)
			keep.push_back(id);  // still on probation
	}
	m_recent.swap(keep);
	return culled;
}

void LocalMapper::fuseInto(
	KeyFrameId target, const std::vector<LandmarkId>& lms, const PinholeIntrinsics& K, LocalMappingReport& rep)
{
	auto& kf = m_map.keyframe(target);
	const auto& f = kf.features;
	const auto T_cam_world = -kf.T_world_cam;
	const Eigen::Vector3d center = kf.cameraCenter();
	const float maxDist = f.isBinary() ? m_opts.fuseMaxDistanceOrb : m_matcher.maxDistanceSift * 0.8f;
	std::vector<int> area;
	for (LandmarkId id : lms)
	{
		if (!m_map.hasLandmark(id)) continue;
		const auto& lm = m_map.landmark(id);
		if (lm.observations.count(target)) continue;
		ProjectedLandmark p;
		if (!projectLandmark(lm, T_cam_world, center, K, f, m_matcher, p)) continue;
		const float r = m_opts.fuseRadius * static_cast<float>(f.levelScale[p.predictedLevel]);
		int best = -1;
		float bestD = maxDist + 1;
		f.featuresInArea(p.u, p.v, r, std::max(0, p.predictedLevel - 1), p.predictedLevel + 1, area);
		for (int i : area)
		{
			const float d = f.depth[i];
			if (d > 0 && std::abs(d - p.depth) > m_matcher.maxDepthError * p.depth) continue;
			const float dist = descriptorDistance(lm.descriptor, 0, f.descriptors, i);
			if (dist < bestD)
			{
				bestD = dist;
				best = i;
			}
		}
		if (best < 0 || bestD > maxDist) continue;
		const LandmarkId there = kf.landmarks[best];
		if (there == kNoLandmark || !m_map.hasLandmark(there))
		{
			m_map.addObservation(id, target, best);
			rep.addedObservations++;
		}
		else if (there != id)
		{
			// Duplicates: keep the better-observed landmark.
			const bool keepThere = m_map.landmark(there).observations.size() >= lm.observations.size();
			m_map.replaceLandmark(keepThere ? id : there, keepThere ? there : id);
			rep.fusedLandmarks++;
		}
	}
}

int LocalMapper::fuseLandmarks(KeyFrameId target, const std::vector<LandmarkId>& lms, const PinholeIntrinsics& K)
{
	LocalMappingReport rep;
	fuseInto(target, lms, K, rep);
	return rep.fusedLandmarks + rep.addedObservations;
}

void LocalMapper::fuse(KeyFrameId kfId, const PinholeIntrinsics& K, LocalMappingReport& rep)
{
	const auto neighbours = m_map.bestCovisibles(kfId, static_cast<std::size_t>(m_opts.fuseNeighbours));
	std::vector<LandmarkId> mine;
	for (LandmarkId l : m_map.keyframe(kfId).landmarks)
		if (l != kNoLandmark) mine.push_back(l);
	for (KeyFrameId n : neighbours) fuseInto(n, mine, K, rep);
	std::vector<LandmarkId> theirs;
	std::set<LandmarkId> seen;
	for (KeyFrameId n : neighbours)
		for (LandmarkId l : m_map.keyframe(n).landmarks)
			if (l != kNoLandmark && seen.insert(l).second) theirs.push_back(l);
	fuseInto(kfId, theirs, K, rep);
	for (LandmarkId l : m_map.keyframe(kfId).landmarks)
		if (l != kNoLandmark && m_map.hasLandmark(l)) m_map.updateLandmarkStats(l);
	for (KeyFrameId n : neighbours) m_map.updateCovisibility(n);
}

int LocalMapper::cullKeyFrames(KeyFrameId current)
{
	int culled = 0;
	const KeyFrameId first = m_map.keyframes().begin()->first;
	for (KeyFrameId id : m_map.bestCovisibles(current, 30))
	{
		if (id == first || id == current || !m_map.hasKeyFrame(id)) continue;
		const auto& kf = m_map.keyframe(id);
		int total = 0, redundant = 0;
		for (std::size_t i = 0; i < kf.landmarks.size(); i++)
		{
			const LandmarkId l = kf.landmarks[i];
			if (l == kNoLandmark || !m_map.hasLandmark(l)) continue;
			++total;
			const int level = kf.features.keypoints[i].octave;
			int others = 0;
			for (const auto& [okf, okp] : m_map.landmark(l).observations)
			{
				if (okf == id) continue;
				if (m_map.keyframe(okf).features.keypoints[okp].octave <= level + 1 && ++others >= 3) break;
			}
			if (others >= 3) ++redundant;
		}
		if (total > 0 && redundant > m_opts.redundantKeyFrameRatio * total)
		{
			m_map.eraseKeyFrame(id);
			++culled;
		}
	}
	return culled;
}

}  // namespace keygrid::sfm
