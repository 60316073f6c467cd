#pragma once
/** \file RigidRansac.h
 * Geometric verification of a loop candidate with depth: 3D-3D correspondences p_a[i] <-> p_b[i]
 * (points of matched features back-projected with their depth, each in its keyframe's camera
 * frame) -> T_a_b with p_a ~= T_a_b p_b, by RANSAC over minimal sets of 3 pairs, closed-form
 * Horn/Umeyama fits (Eigen::umeyama), then refinement on the inliers until the set is stable.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <vector>

namespace keygrid::loop
{
struct RigidRansacOptions : public core::FieldTableOptions<RigidRansacOptions>
{
	/** Inlier if |p_a - T_a_b p_b| is below this [m] (Default: 0.05 m) */
	double inlierThreshold{0.05};
	/** Inliers needed to accept the transform (Default: 20) */
	int minInliers{20};
	/** RANSAC hypotheses at most (Default: 300) */
	int maxIterations{300};
	/** Stop once a hypothesis has this probability of being outlier-free (Default: 0.999) */
	double confidence{0.999};
	/** Re-fit on all inliers and re-classify at most this often (Default: 5) */
	int refinementRounds{5};
	/** Estimate a similarity (scale) instead of a rigid transform (Default: false) */
	bool estimateScale{false};
	/** Seed of the sampler: the same inputs and seed give the same result (Default: 42) */
	std::uint64_t seed{42};

	/** The INI keys, with description and rule (core/OptionFields.h). */
	core::OptionFields fields();
	/** Throws std::invalid_argument("[section] key = value (must be ...)") on a bad value. */
	void validate(const std::string& section = "ransac") const;
	/** validate() as a flag, its message in `why`. */
	bool isValid(std::string* why = nullptr) const;
};

struct RigidRansacResult
{
	bool success{false};       //!< at least minInliers inliers
	Eigen::Isometry3d T_a_b{Eigen::Isometry3d::Identity()};  //!< rotation + translation
	double scale{1.0};         //!< 1 unless estimateScale (then p_a = s R p_b + t)
	std::vector<char> inlier;  //!< per correspondence
	int numInliers{0};
	double rmse{0};            //!< RMS residual of the inliers [m]
	int iterations{0};         //!< hypotheses tried
};

/** Throws std::invalid_argument for different sizes or invalid options. Fewer than 3 pairs
 * give success = false. */
RigidRansacResult estimateRigidTransformRansac(
	const std::vector<Eigen::Vector3d>& p_a, const std::vector<Eigen::Vector3d>& p_b,
	const RigidRansacOptions& opts = {});

}  // namespace keygrid::loop
