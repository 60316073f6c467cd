#include <keygrid/slam/FinalRefinement.h>
#include <keygrid/sfm/BundleWindow.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <future>

namespace keygrid::slam
{
std::vector<sfm::KeyFrameId> finalWindowSeeds(const std::vector<loop::LoopClosureEvent>& loops, const sfm::SparseMap& map)
{
	std::vector<sfm::KeyFrameId> seeds;
	for (auto it = loops.rbegin(); it != loops.rend(); ++it)
	{
		seeds.push_back(it->keyframe);
		seeds.push_back(it->loopKeyFrame);
	}
	if (map.numKeyFrames() > 0) seeds.push_back(map.keyframes().rbegin()->first);
	return seeds;
}

double scaleBetween(const std::map<sfm::KeyFrameId, mrpt::poses::CPose3D>& before, const std::map<sfm::KeyFrameId, mrpt::poses::CPose3D>& after)
{
	std::vector<Eigen::Vector3d> a, b;
	for (const auto& [id, T0] : before)
		if (const auto it = after.find(id); it != after.end())
		{
			a.emplace_back(T0.x(), T0.y(), T0.z());
			b.emplace_back(it->second.x(), it->second.y(), it->second.z());
		}
	if (a.size() < 2) return 1.0;
	Eigen::Matrix3Xd A(3, a.size()), B(3, b.size());
	for (std::size_t i = 0; i < a.size(); i++)
	{
		A.col(static_cast<Eigen::Index>(i)) = a[i];
		B.col(static_cast<Eigen::Index>(i)) = b[i];
	}
	// Umeyama's similarity B ~ s R A + t: s is the top-left block's column norm.
	const Eigen::Matrix4d T = Eigen::umeyama(A, B, true);
	const double s = T.topLeftCorner<3, 3>().col(0).norm();
	return std::isfinite(s) && s > 0 ? s : 1.0;
}

FinalBundleAdjustment finalBundleAdjustment(
	sfm::SparseMap& map, const sfm::PinholeIntrinsics& K, const std::vector<loop::LoopClosureEvent>& loops,
	const RefinementOptions& rc, const sfm::LocalMapperOptions& mapping, bool holdScale)
{
	std::map<sfm::KeyFrameId, mrpt::poses::CPose3D> before;
	if (holdScale)
		for (const auto& [id, kf] : map.keyframes()) before[id] = kf.T_world_cam;
	auto o = mapping.ba;
	o.iterations = rc.globalIterations;
	o.functionTolerance = 1e-6;
	// The landmarks local mapping would not have triangulated without depth stay out.
	o.minParallaxDegWithoutDepth = mapping.minParallaxDeg;
	FinalBundleAdjustment out;
	const auto maxKf = static_cast<std::size_t>(rc.globalMaxKeyFrames);
	if (maxKf > 0 && map.numKeyFrames() > maxKf)
	{
		const auto w = sfm::growBundleWindow(map, finalWindowSeeds(loops, map), maxKf);
		out.window.emplace(w.local.begin(), w.local.end());
		out.report = sfm::bundleAdjust(map, w.local, w.fixed, K, o);
	}
	else
		out.report = sfm::globalBundleAdjustment(map, K, o);
	if (holdScale)
	{
		std::map<sfm::KeyFrameId, mrpt::poses::CPose3D> after;
		for (const auto& [id, kf] : map.keyframes()) after[id] = kf.T_world_cam;
		const double s = scaleBetween(before, after);
		if (s != 1.0)
		{
			// About the world origin: the reprojection errors stay what the adjustment left.
			map.rescale(1.0 / s);
			out.undoneScale = s;
		}
	}
	return out;
}

double largestDisplacement(
	const std::map<sfm::KeyFrameId, mrpt::poses::CPose3D>& before,
	const std::map<sfm::KeyFrameId, mrpt::poses::CPose3D>& after, double depth)
{
	double worst = 0;
	const mrpt::math::TPoint3D ahead(0, 0, depth);  // optical frame: z forward
	for (const auto& [id, T0] : before)
	{
		const auto it = after.find(id);
		if (it == after.end()) continue;
		const auto& T1 = it->second;
		worst = std::max(worst, (T1.translation() - T0.translation()).norm());
		worst = std::max(worst, (T1.composePoint(ahead) - T0.composePoint(ahead)).norm());
	}
	return worst;
}

std::vector<std::optional<mrpt::poses::CPose3D>> refineFramePoses(
	const std::vector<sfm::TrackedFrame>& frames, const core::Trajectory& base, const sfm::SparseMap& map,
	const sfm::PinholeIntrinsics& K, const sfm::PoseOptimizerOptions& pose, int minInliers,
	const std::function<bool(const sfm::TrackedFrame&)>& select)
{
	std::vector<std::optional<mrpt::poses::CPose3D>> refined(frames.size());
	// A landmark fused into another since the frame matched it: the survivor stands for it.
	const std::vector<const sfm::Landmark*> landmarks = map.resolvedLandmarks();
	const auto landmarkOf = [&](sfm::LandmarkId id) -> const sfm::Landmark* {
		return id < landmarks.size() ? landmarks[static_cast<std::size_t>(id)] : nullptr;
	};
	const auto refine = [&](std::size_t first)
	{
		for (std::size_t i = first; i < frames.size(); i += 2)
		{
			const auto& f = frames[i];
			if (!f.tracked || !select(f)) continue;
			std::vector<sfm::PoseObservation> obs;
			obs.reserve(f.observations.size());
			for (std::size_t k = 0; k < f.observations.size(); k++)
			{
				const sfm::Landmark* lm = landmarkOf(f.observedLandmarks[k]);
				if (!lm) continue;
				obs.push_back(f.observations[k].toPoseObservation(lm->p_world));
			}
			if (static_cast<int>(obs.size()) < minInliers) continue;
			auto T = base[i].T_world_cam;
			const auto r = sfm::optimizePose(T, obs, K, pose);
			if (r.inliers >= minInliers) refined[i] = T;
		}
	};
	// std::async's future joins in its destructor and passes an exception on through get().
	auto second = std::async(std::launch::async, refine, std::size_t{1});
	refine(0);
	second.get();
	return refined;
}

}  // namespace keygrid::slam
