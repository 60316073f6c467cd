#include "RansacSampling.h"

#include <keygrid/loop/RigidRansac.h>
#include <mrpt/config/CConfigFileBase.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace keygrid::loop
{
core::OptionFields RigidRansacOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("inlier_threshold", inlierThreshold, "3D distance for inliers [m]", R::positive());
	f.add("min_inliers", minInliers, "inliers needed to accept", R::atLeast(3));
	f.add("max_iterations", maxIterations, "RANSAC hypotheses at most", R::atLeast(1));
	f.add("confidence", confidence, "early stop probability", R::between(0, 1));
	f.add("refinement_rounds", refinementRounds, "re-fits on inliers", R::atLeast(0));
	f.add("estimate_scale", estimateScale, "Sim(3) instead of SE(3)");
	f.add("seed", seed, "sampler seed");
	return f;
}

void RigidRansacOptions::validate(const std::string& section) const { core::validateFields(*this, section); }

bool RigidRansacOptions::isValid(std::string* why) const
{
	try
	{
		validate();
	}
	catch (const std::invalid_argument& e)
	{
		if (why) *why = e.what();
		return false;
	}
	return true;
}

namespace
{
/** Umeyama fit of dst ~= s R src + t on the listed pairs; returns false when degenerate. */
bool fit(
	const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b, const std::vector<int>& idx,
	bool withScale, Eigen::Matrix4d& T)
{
	Eigen::Matrix3Xd src(3, idx.size()), dst(3, idx.size());
	for (std::size_t i = 0; i < idx.size(); ++i)
	{
		src.col(static_cast<Eigen::Index>(i)) = b[static_cast<std::size_t>(idx[i])];
		dst.col(static_cast<Eigen::Index>(i)) = a[static_cast<std::size_t>(idx[i])];
	}
	T = Eigen::umeyama(src, dst, withScale);
	return T.allFinite();
}

/** Classifies pairs; returns the inlier count and the sum of squared inlier residuals. */
int classify(
	const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b, const Eigen::Matrix4d& T,
	double thr2, std::vector<char>& inlier, double& sse)
{
	const Eigen::Matrix3d sR = T.topLeftCorner<3, 3>();
	const Eigen::Vector3d t = T.topRightCorner<3, 1>();
	int n = 0;
	sse = 0;
	for (std::size_t i = 0; i < a.size(); ++i)
	{
		const double e2 = (a[i] - (sR * b[i] + t)).squaredNorm();
		inlier[i] = e2 < thr2;
		if (inlier[i])
		{
			++n;
			sse += e2;
		}
	}
	return n;
}
}  // namespace

RigidRansacResult estimateRigidTransformRansac(
	const std::vector<Eigen::Vector3d>& p_a, const std::vector<Eigen::Vector3d>& p_b, const RigidRansacOptions& opts)
{
	if (p_a.size() != p_b.size())
		throw std::invalid_argument(
			"estimateRigidTransformRansac: " + std::to_string(p_a.size()) + " vs " + std::to_string(p_b.size()) + " points");
	opts.validate();
	RigidRansacResult res;
	const std::size_t n = p_a.size();
	res.inlier.assign(n, 0);
	if (n < 3) return res;

	const double thr2 = opts.inlierThreshold * opts.inlierThreshold;
	std::vector<char> inl(n);
	Eigen::Matrix4d best = Eigen::Matrix4d::Identity();
	int bestCount = -1;
	double bestSse = 0;
	res.iterations = detail::runRansacHypotheses(
		opts.seed, n, opts.maxIterations, opts.confidence,
		[&](const std::size_t s[3]) -> std::optional<int>
		{
			// Degenerate samples (collinear or coincident points) do not fix a rotation.
			const double areaB = (p_b[s[1]] - p_b[s[0]]).cross(p_b[s[2]] - p_b[s[0]]).norm();
			const double areaA = (p_a[s[1]] - p_a[s[0]]).cross(p_a[s[2]] - p_a[s[0]]).norm();
			if (areaA < 1e-3 * thr2 || areaB < 1e-3 * thr2) return std::nullopt;
			Eigen::Matrix4d T;
			if (!fit(p_a, p_b, {static_cast<int>(s[0]), static_cast<int>(s[1]), static_cast<int>(s[2])}, opts.estimateScale, T))
				return std::nullopt;
			double sse;
			const int count = classify(p_a, p_b, T, thr2, inl, sse);
			const bool better = count > bestCount || (count == bestCount && sse < bestSse);
			if (!better) return std::nullopt;
			bestCount = count;
			bestSse = sse;
			best = T;
			return count;
		});
	if (bestCount < 3) return res;

	// Refinement: least-squares fit on all inliers, re-classify, until the set stops changing.
	double sse = 0;
	int count = classify(p_a, p_b, best, thr2, inl, sse);
	for (int r = 0; r < opts.refinementRounds && count >= 3; ++r)
	{
		std::vector<int> idx;
		for (std::size_t i = 0; i < n; ++i)
			if (inl[i]) idx.push_back(static_cast<int>(i));
		Eigen::Matrix4d T;
		if (!fit(p_a, p_b, idx, opts.estimateScale, T)) break;
		std::vector<char> inl2(n);
		double sse2;
		const int count2 = classify(p_a, p_b, T, thr2, inl2, sse2);
		if (count2 < count) break;  // keep the larger consensus
		const bool same = inl2 == inl;
		best = T;
		inl = std::move(inl2);
		count = count2;
		sse = sse2;
		if (same) break;
	}
	res.numInliers = count;
	res.inlier = inl;
	res.rmse = count > 0 ? std::sqrt(sse / count) : 0.0;
	res.scale = opts.estimateScale ? best.topLeftCorner<3, 3>().col(0).norm() : 1.0;
	res.T_a_b.linear() = best.topLeftCorner<3, 3>() / res.scale;
	res.T_a_b.translation() = best.topRightCorner<3, 1>();
	res.success = count >= opts.minInliers;
	return res;
}

}  // namespace keygrid::loop
