#pragma once
/** \file Sim3Ransac.h
 * Geometric verification of a monocular loop candidate (ORB-SLAM2's Sim3Solver and
 * OptimizeSim3): matched map points of two keyframes, each in its keyframe's camera frame and
 * units, -> the similarity S_a_b with p_a ~= s R p_b + t. Hypotheses are closed-form
 * Horn/Umeyama fits with scale on 3 random pairs; a pair is an inlier when each point projects
 * into the other keyframe's image close to the keypoint it was matched with (the monocular map
 * has no depth to compare 3D distances in, and its units are arbitrary, so distances are
 * measured in pixels). With fixScale the fits are rigid (s = 1). The best hypothesis is then refined on its inliers by minimising those
 * reprojection errors (Ceres, Huber loss) and the inliers re-classified.
 */
#include <keygrid/loop/Sim3.h>
#include <keygrid/core/PinholeIntrinsics.h>

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace keygrid::loop
{
struct Sim3RansacOptions
{
	/** Inlier if both squared reprojection errors are below this x sigma^2, sigma the keypoint's
	 * pyramid scale [px] (Default: 9.21, the 99 % chi-square quantile for 2 DOF, as ORB-SLAM) */
	double inlierChi2{9.21};
	/** Inliers needed to accept the similarity, after refinement (Default: 20, ORB-SLAM's) */
	int minInliers{20};
	/** RANSAC hypotheses at most (Default: 300) */
	int maxIterations{300};
	/** Stop once a hypothesis has this probability of being outlier-free (Default: 0.99) */
	double confidence{0.99};
	/** Reprojection refinements on the inliers, each followed by re-classification (Default: 2) */
	int refinementRounds{2};
	/** Seed of the sampler: the same inputs and seed give the same result (Default: 42) */
	std::uint64_t seed{42};
	/** Both keyframes' points are in the same known units (a monocular map made metric by
	 * slam::MetricScale): the scale is held at 1 (hypotheses are rigid Umeyama fits, the
	 * refinement moves rotation and translation only), as ORB-SLAM fixes it once the scale is
	 * observable. A few tens of matches over a short baseline measure the scale far worse than
	 * the floor does, and a scale taken from them would be spread over the loop (Default: false) */
	bool fixScale{false};

	/** Throws std::invalid_argument naming the first invalid field and its value. */
	void validate() const;
};

/** One matched pair: the same scene point as seen by keyframes a and b. */
struct Sim3Match
{
	Eigen::Vector3d p_a, p_b;  //!< map point in a's / b's camera frame (each in its map units)
	Eigen::Vector2d uv_a, uv_b;  //!< the matched keypoints (undistorted) [px]
	double sigma_a{1}, sigma_b{1};  //!< their pixel standard deviations (pyramid scale) [px]
};

struct Sim3RansacResult
{
	bool success{false};  //!< at least minInliers inliers after refinement
	Sim3 S_a_b;  //!< b's camera coordinates -> a's
	std::vector<char> inlier;  //!< per match
	int numInliers{0};
	int iterations{0};  //!< hypotheses tried
};

/** Throws std::invalid_argument for invalid options. Fewer than 3 matches give success = false.
 * Points behind either camera never count as inliers. */
Sim3RansacResult estimateSim3Ransac(
	const std::vector<Sim3Match>& matches, const core::PinholeIntrinsics& K, const Sim3RansacOptions& opts = {});

/** Squared reprojection errors [px^2] of a match under S_a_b: of p_b mapped into a's image and of
 * p_a mapped into b's; infinite when the point lies behind the camera. */
Eigen::Vector2d sim3ReprojectionErrors(const Sim3Match& m, const Sim3& S_a_b, const core::PinholeIntrinsics& K);

}  // namespace keygrid::loop
