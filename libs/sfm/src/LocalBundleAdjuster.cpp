#include <keygrid/sfm/LocalBundleAdjuster.h>
#include <mrpt/config/CConfigFileBase.h>

#include <ceres/ceres.h>
#include <array>
#include <set>

namespace keygrid::sfm
{
void BundleAdjusterOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	windowSize = c.read_int(s, "window_size", windowSize);
	maxFixedKeyFrames = c.read_int(s, "max_fixed_keyframes", maxFixedKeyFrames);
	iterations = c.read_int(s, "iterations", iterations);
	threads = c.read_int(s, "threads", threads);
	if (windowSize < 1) throw std::invalid_argument("[" + s + "] window_size = " + std::to_string(windowSize) + " (must be >= 1)");
	if (iterations < 1) throw std::invalid_argument("[" + s + "] iterations = " + std::to_string(iterations) + " (must be >= 1)");
	if (threads < 1) throw std::invalid_argument("[" + s + "] threads = " + std::to_string(threads) + " (must be >= 1)");
}

void BundleAdjusterOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	c.write(s, "window_size", windowSize, 30, 40, "covisible keyframes optimised with the new one");
	c.write(s, "max_fixed_keyframes", maxFixedKeyFrames, 30, 40, "fixed keyframes anchoring the window");
	c.write(s, "iterations", iterations, 30, 40, "Levenberg-Marquardt iterations");
	c.write(s, "threads", threads, 30, 40, "Ceres threads (1 = deterministic)");
}

BundleAdjusterReport localBundleAdjustment(
	SparseMap& map, KeyFrameId kfId, const PinholeIntrinsics& K, const BundleAdjusterOptions& o)
{
	// --- Window: the keyframe and its best covisibles; landmarks they see; fixed observers.
	std::vector<KeyFrameId> local = {kfId};
	for (KeyFrameId id : map.bestCovisibles(kfId, static_cast<std::size_t>(o.windowSize))) local.push_back(id);
	std::set<KeyFrameId> localSet(local.begin(), local.end());
	std::map<KeyFrameId, int> fixedCount;
	std::set<LandmarkId> lms;
	for (KeyFrameId id : local)
		for (LandmarkId lm : map.keyframe(id).landmarks)
			if (lm != kNoLandmark && map.hasLandmark(lm) && lms.insert(lm).second)
				for (const auto& [kf, kp] : map.landmark(lm).observations)
					if (!localSet.count(kf)) fixedCount[kf]++;
	std::vector<std::pair<int, KeyFrameId>> fixedSorted;
	for (const auto& [kf, c] : fixedCount) fixedSorted.emplace_back(-c, kf);
	std::sort(fixedSorted.begin(), fixedSorted.end());
	std::set<KeyFrameId> fixedSet;
	for (std::size_t i = 0; i < fixedSorted.size() && static_cast<int>(i) < o.maxFixedKeyFrames; i++)
		fixedSet.insert(fixedSorted[i].second);
	return bundleAdjust(map, local, fixedSet, K, o);
}

BundleAdjusterReport globalBundleAdjustment(
	SparseMap& map, const PinholeIntrinsics& K, const BundleAdjusterOptions& o)
{
	std::vector<KeyFrameId> all;
	for (const auto& [id, kf] : map.keyframes()) all.push_back(id);
	return bundleAdjust(map, all, {}, K, o);
}

BundleAdjusterReport bundleAdjust(
	SparseMap& map, const std::vector<KeyFrameId>& local, const std::set<KeyFrameId>& fixedSet,
	const PinholeIntrinsics& K, const BundleAdjusterOptions& o)
{
	BundleAdjusterReport rep;
	if (local.empty()) return rep;
	std::set<LandmarkId> lms;
	for (KeyFrameId id : local)
		for (LandmarkId lm : map.keyframe(id).landmarks)
			if (lm != kNoLandmark && map.hasLandmark(lm)) lms.insert(lm);

	// --- Parameter blocks.
	std::map<KeyFrameId, std::array<double, 7>> poses;  // q(x,y,z,w), t of T_cam_world
	for (KeyFrameId id : local) toCeres(map.keyframe(id).T_world_cam, poses[id].data(), poses[id].data() + 4);
	for (KeyFrameId id : fixedSet) toCeres(map.keyframe(id).T_world_cam, poses[id].data(), poses[id].data() + 4);
	std::map<LandmarkId, std::array<double, 3>> points;
	for (LandmarkId lm : lms)
	{
		const auto& p = map.landmark(lm).p_world;
		points[lm] = {p.x(), p.y(), p.z()};
	}

	ceres::Problem::Options po;
	po.manifold_ownership = ceres::TAKE_OWNERSHIP;
	ceres::Problem problem(po);
	for (auto& [id, pq] : poses)
	{
		problem.AddParameterBlock(pq.data(), 4, new ceres::EigenQuaternionManifold());
		problem.AddParameterBlock(pq.data() + 4, 3);
		// Gauge: keyframe 0 defines the world frame and never moves; fixed observers anchor
		// the window to the rest of the map.
		if (fixedSet.count(id) || id == map.keyframes().begin()->first)
		{
			problem.SetParameterBlockConstant(pq.data());
			problem.SetParameterBlockConstant(pq.data() + 4);
		}
	}
	struct Obs
	{
		LandmarkId lm;
		KeyFrameId kf;
		bool rgbd;
		ceres::ResidualBlockId block;
	};
	std::vector<Obs> all;
	for (LandmarkId lm : lms)
	{
		for (const auto& [kf, kp] : map.landmark(lm).observations)
		{
			if (!poses.count(kf)) continue;
			const auto& f = map.keyframe(kf).features;
			const Eigen::Vector2d uv(f.undistorted[kp].x, f.undistorted[kp].y);
			const double invSigma = 1.0 / f.levelScale[f.keypoints[kp].octave];
			const double d = f.depth[kp];
			const bool rgbd = d > 0 && d < o.maxDepthForRgbd;
			ceres::CostFunction* cost =
				rgbd ? static_cast<ceres::CostFunction*>(new ceres::AutoDiffCostFunction<RgbdReprojectionCost, 3, 4, 3, 3>(
						   new RgbdReprojectionCost(uv, d, o.bf, invSigma, K)))
					 : new ceres::AutoDiffCostFunction<MonoReprojectionCost, 2, 4, 3, 3>(
						   new MonoReprojectionCost(uv, invSigma, K));
			auto& pq = poses[kf];
			const auto block = problem.AddResidualBlock(
				cost, new ceres::HuberLoss(std::sqrt(rgbd ? o.chi2Rgbd : o.chi2Mono)), pq.data(), pq.data() + 4,
				points[lm].data());
			all.push_back({lm, kf, rgbd, block});
		}
	}
	rep.keyframes = static_cast<int>(local.size());
	rep.fixedKeyFrames = static_cast<int>(fixedSet.size());
	rep.landmarks = static_cast<int>(lms.size());
	rep.observations = static_cast<int>(all.size());
	if (all.empty()) return rep;

	ceres::Solver::Options so;
	so.linear_solver_type = ceres::SPARSE_SCHUR;
	so.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
	so.max_num_iterations = o.iterations;
	so.num_threads = o.threads;
	so.logging_type = ceres::SILENT;
	ceres::Solver::Summary summary;
	ceres::Solve(so, &problem, &summary);
	rep.initialCost = summary.initial_cost;
	rep.finalCost = summary.final_cost;

	// --- Write back, then drop observations that remain outliers (plain chi-square).
	for (KeyFrameId id : local) map.keyframe(id).T_world_cam = fromCeres(poses[id].data(), poses[id].data() + 4);
	for (LandmarkId lm : lms) map.landmark(lm).p_world = Eigen::Vector3d(points[lm][0], points[lm][1], points[lm][2]);
	for (const auto& ob : all)
	{
		double cost = 0;
		problem.EvaluateResidualBlock(ob.block, false, &cost, nullptr, nullptr);
		// EvaluateResidualBlock(apply_loss_function=false) gives 0.5 |r|^2.
		if (2.0 * cost > (ob.rgbd ? o.chi2Rgbd : o.chi2Mono) || !map.hasLandmark(ob.lm))
		{
			if (map.hasLandmark(ob.lm))
			{
				map.eraseObservation(ob.lm, ob.kf);
				rep.outliersRemoved++;
			}
		}
	}
	for (LandmarkId lm : lms)
		if (map.hasLandmark(lm)) map.updateLandmarkStats(lm);
	return rep;
}

}  // namespace keygrid::sfm
