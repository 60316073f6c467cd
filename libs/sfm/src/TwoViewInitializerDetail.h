#pragma once
/** \file TwoViewInitializerDetail.h
 * Internals of TwoViewInitializer shared by its .cpp files (not installed): the RANSAC model
 * fits and scores (TwoViewInitializer_models.cpp) and the check of one motion hypothesis by
 * triangulation (TwoViewInitializer_reconstruct.cpp).
 */
#include <keygrid/sfm/TwoViewInitializer.h>

#include <array>
#include <vector>

namespace keygrid::sfm::detail
{
/** 95 % quantiles of chi-square with 1 and 2 degrees of freedom. */
constexpr double kChi2OneDof = 3.84, kChi2TwoDof = 5.99;

/** The correspondences with the inverse variance 1 / (sigmaPx scale)^2 of each one per view,
 * and of a residual that compares the two views, 1 / (sigma_ref^2 + sigma_cur^2). */
struct WeightedMatches
{
	const TwoViewMatches* m{nullptr};
	std::vector<double> invVarRef, invVarCur, invVarPair;
	std::size_t size() const { return m->px_ref.size(); }
};

/** A model with its paper score S_M = sum over correspondences and views of
 * (th - d^2 / sigma^2) for the terms below the chi-square gate, and its inliers. */
struct ModelFit
{
	bool valid{false};
	Eigen::Matrix3d M{Eigen::Matrix3d::Zero()};
	double score{0};
	std::vector<uint8_t> inliers;
	int numInliers{0};
};

using MinimalSet = std::array<int, 8>;

/** iterations draws of 8 distinct indices in [0, n) from a 64-bit Mersenne twister seeded with
 * seed (rng() % k: deterministic on every platform, unlike std::uniform_int_distribution). */
std::vector<MinimalSet> drawMinimalSets(std::size_t n, int iterations, uint64_t seed);

/** Score of H (symmetric transfer error, gate and score 5.99 per view); fills inliers. */
double scoreHomography(const Eigen::Matrix3d& H, const WeightedMatches& w, std::vector<uint8_t>& inliers);
/** Score of F (point-to-epipolar-line distance, gate 3.84, score 5.99 per view). */
double scoreFundamental(const Eigen::Matrix3d& F, const WeightedMatches& w, std::vector<uint8_t>& inliers);

/** RANSAC over the draws (H from the first 4 indices of each), then one refit on all inliers
 * kept when it scores higher. */
ModelFit fitHomography(const WeightedMatches& w, const std::vector<MinimalSet>& sets);
/** RANSAC over the draws (8-point), then one refit on all inliers kept when it scores higher. */
ModelFit fitFundamental(const WeightedMatches& w, const std::vector<MinimalSet>& sets);

/** One motion hypothesis checked on the model's inliers. */
struct HypothesisCheck
{
	int good{0};  //!< inliers passing cheirality (when parallax allows) and reprojection
	int numValid{0};  //!< good points also above the per-point parallax
	double medianParallaxDeg{0};  //!< over the good points
	std::vector<Eigen::Vector3d> points_ref;  //!< per correspondence, set where good
	std::vector<uint8_t> goodMask, valid;  //!< per correspondence
};

/** Levenberg-Marquardt on the Sampson error of the masked pairs over the 5 degrees of freedom
 * of the motion (rotation, translation direction), from the given motion, alternated with
 * re-gating every pair on the refined motion (mask is updated: the pairs whose Sampson error
 * passes chi2(1) at 95 %). */
RelativeMotion refineMotion(
	const RelativeMotion& motion, const PinholeIntrinsics& K, const WeightedMatches& w, std::vector<uint8_t>& mask);

HypothesisCheck checkMotion(
	const RelativeMotion& motion, const PinholeIntrinsics& K, const WeightedMatches& w,
	const std::vector<uint8_t>& inliers, const TwoViewOptions& opts);

}  // namespace keygrid::sfm::detail
