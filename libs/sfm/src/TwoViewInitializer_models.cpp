// TwoViewInitializer, model estimation: the shared RANSAC draws, the homography and
// fundamental-matrix fits and their chi-square scores (Mur-Artal et al. 2015, IV-B).
#include "TwoViewInitializerDetail.h"

#include <Eigen/Dense>

#include <algorithm>
#include <limits>
#include <numeric>
#include <random>

namespace keygrid::sfm::detail
{
namespace
{
/** Squared distance [px^2] of x to the line l = (a, b, c): (l . x)^2 / (a^2 + b^2). */
double lineDistance2(const Eigen::Vector3d& l, const Eigen::Vector2d& x)
{
	const double num = l.x() * x.x() + l.y() * x.y() + l.z();
	const double den = l.x() * l.x() + l.y() * l.y();
	return den > 0 ? num * num / den : std::numeric_limits<double>::infinity();
}

/** Squared distance [px^2] of x to the transfer M p (dehomogenised). */
double transferDistance2(const Eigen::Matrix3d& M, const Eigen::Vector2d& p, const Eigen::Vector2d& x)
{
	const Eigen::Vector3d q = M * Eigen::Vector3d(p.x(), p.y(), 1.0);
	if (q.z() == 0) return std::numeric_limits<double>::infinity();
	return (q.head<2>() / q.z() - x).squaredNorm();
}

/** One gated score term: (th_score - chi2) when chi2 <= gate, else 0 and the pair is out. */
double term(double chi2, double gate, double scoreTh, bool& in)
{
	if (!(chi2 <= gate))
	{
		in = false;
		return 0.0;
	}
	return scoreTh - chi2;
}

/** The pairs with a nonzero mask entry, or with the given indices. */
void gather(const WeightedMatches& w, const std::vector<uint8_t>& mask, std::vector<Eigen::Vector2d>& a, std::vector<Eigen::Vector2d>& b)
{
	a.clear();
	b.clear();
	for (std::size_t i = 0; i < w.size(); i++)
		if (mask[i])
		{
			a.push_back(w.m->px_ref[i]);
			b.push_back(w.m->px_cur[i]);
		}
}

/** RANSAC skeleton shared by both models: estimate on each draw (first k indices), keep the
 * best score, then refit on its inliers and keep the refit if it scores higher. */
template <typename Estimate, typename Score>
ModelFit ransac(const WeightedMatches& w, const std::vector<MinimalSet>& sets, std::size_t k, Estimate estimate, Score score)
{
	ModelFit best;
	std::vector<Eigen::Vector2d> a(k), b(k);
	std::vector<uint8_t> inl;
	for (const auto& set : sets)
	{
		for (std::size_t j = 0; j < k; j++)
		{
			a[j] = w.m->px_ref[static_cast<std::size_t>(set[j])];
			b[j] = w.m->px_cur[static_cast<std::size_t>(set[j])];
		}
		Eigen::Matrix3d M;
		if (!estimate(a, b, M)) continue;
		const double s = score(M, w, inl);
		if (!best.valid || s > best.score) best = {true, M, s, inl, 0};
	}
	if (!best.valid) return best;
	gather(w, best.inliers, a, b);
	Eigen::Matrix3d M;
	if (estimate(a, b, M))
	{
		const double s = score(M, w, inl);
		if (s > best.score) best = {true, M, s, inl, 0};
	}
	best.numInliers = static_cast<int>(std::count(best.inliers.begin(), best.inliers.end(), uint8_t{1}));
	return best;
}
}  // namespace

std::vector<MinimalSet> drawMinimalSets(std::size_t n, int iterations, uint64_t seed)
{
	std::vector<MinimalSet> sets;
	if (n < 8) return sets;
	std::mt19937_64 rng(seed);
	std::vector<int> pool(n);
	sets.resize(static_cast<std::size_t>(iterations));
	for (auto& set : sets)
	{
		// Partial Fisher-Yates: the first 8 entries of pool become a uniform draw without
		// replacement; pool stays a permutation, so no reset is needed between draws.
		std::iota(pool.begin(), pool.end(), 0);
		for (std::size_t j = 0; j < 8; j++)
		{
			const std::size_t r = j + static_cast<std::size_t>(rng() % (n - j));
			std::swap(pool[j], pool[r]);
			set[j] = pool[j];
		}
	}
	return sets;
}

/* Symmetric transfer error: d_cur = |x_cur - H x_ref|, d_ref = |x_ref - H^-1 x_cur|, each a
 * 2-dof residual. Both keypoints are noisy, so to first order (H's Jacobian ~ identity at the
 * small motions of an initialization) its variance per axis is sigma_ref^2 + sigma_cur^2 and
 * d^2 / (sigma_ref^2 + sigma_cur^2) ~ chi2(2), gated at its 95 % quantile 5.99. (ORB-SLAM2's
 * code divides by one view's sigma^2, which rejects 22 % of true inliers instead of 5 %.)
 * A pair is an inlier when both terms pass. The score rewards small residuals linearly
 * (th - chi2), which ranks models better than an inlier count. */
double scoreHomography(const Eigen::Matrix3d& H, const WeightedMatches& w, std::vector<uint8_t>& inliers)
{
	const Eigen::Matrix3d Hinv = H.inverse();
	inliers.assign(w.size(), 0);
	if (!Hinv.allFinite()) return 0.0;
	double score = 0;
	for (std::size_t i = 0; i < w.size(); i++)
	{
		const auto& xr = w.m->px_ref[i];
		const auto& xc = w.m->px_cur[i];
		bool in = true;
		score += term(transferDistance2(H, xr, xc) * w.invVarPair[i], kChi2TwoDof, kChi2TwoDof, in);
		score += term(transferDistance2(Hinv, xc, xr) * w.invVarPair[i], kChi2TwoDof, kChi2TwoDof, in);
		inliers[i] = in ? 1 : 0;
	}
	return score;
}

/* Epipolar distance: x_cur to the line F x_ref and x_ref to F^T x_cur, 1-dof residuals of
 * variance sigma_ref^2 + sigma_cur^2 (the line moves with the other keypoint) gated at
 * chi2(1)'s 95 % quantile 3.84; scored with 5.99 as H is, so that one well-fitted pair is worth
 * about the same in both models and the ratio R_H compares how many pairs each explains. */
double scoreFundamental(const Eigen::Matrix3d& F, const WeightedMatches& w, std::vector<uint8_t>& inliers)
{
	inliers.assign(w.size(), 0);
	double score = 0;
	for (std::size_t i = 0; i < w.size(); i++)
	{
		const auto& xr = w.m->px_ref[i];
		const auto& xc = w.m->px_cur[i];
		bool in = true;
		const Eigen::Vector3d l_cur = F * Eigen::Vector3d(xr.x(), xr.y(), 1.0);
		const Eigen::Vector3d l_ref = F.transpose() * Eigen::Vector3d(xc.x(), xc.y(), 1.0);
		score += term(lineDistance2(l_cur, xc) * w.invVarPair[i], kChi2OneDof, kChi2TwoDof, in);
		score += term(lineDistance2(l_ref, xr) * w.invVarPair[i], kChi2OneDof, kChi2TwoDof, in);
		inliers[i] = in ? 1 : 0;
	}
	return score;
}

ModelFit fitHomography(const WeightedMatches& w, const std::vector<MinimalSet>& sets)
{
	return ransac(w, sets, 4, homographyDlt, scoreHomography);
}

ModelFit fitFundamental(const WeightedMatches& w, const std::vector<MinimalSet>& sets)
{
	return ransac(w, sets, 8, fundamentalEightPoint, scoreFundamental);
}

}  // namespace keygrid::sfm::detail
