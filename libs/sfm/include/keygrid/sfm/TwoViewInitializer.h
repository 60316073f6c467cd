#pragma once
/** \file TwoViewInitializer.h
 * Monocular map start from two views, as ORB-SLAM's initializer (Mur-Artal et al. 2015,
 * section IV): a homography and a fundamental matrix are estimated by RANSAC on the same
 * minimal-set draws and scored in parallel; R_H = S_H / (S_H + S_F) picks the homography
 * (planar or low-parallax scene) above a threshold, else the fundamental matrix; the chosen
 * model's motion hypotheses (4 from E = K^T F K, 8 from the homography) are each checked by
 * triangulating the inliers (cheirality, reprojection, parallax), and the map starts only when
 * one hypothesis is clearly the best with enough parallax. Otherwise the result says why, and
 * the caller retries with a later current frame (or a new reference frame): a sequence that
 * only rotates never initializes, and is reported as LowParallax.
 *
 * Differences from the paper, each for a measured reason (see the tests):
 *  - chi-square tests of residuals that compare the two views use their variance
 *    sigma_ref^2 + sigma_cur^2 (both keypoints are noisy), not one view's sigma^2;
 *  - the homography is also selected when it explains nearly all of F's inliers (F is then
 *    degenerate; R_H alone sits at ~0.44 on an exact plane: TwoViewOptions::homographyInlierShare);
 *  - the best hypothesis is refined (Levenberg-Marquardt on the Sampson error, inliers re-gated)
 *    before its points are triangulated: the linear estimates are several times less accurate
 *    than the noise allows.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>
#include <keygrid/sfm/RgbdReprojectionCost.h>
#include <keygrid/sfm/TwoViewGeometry.h>
#include <mrpt/config/CConfigFileBase.h>

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace keygrid::sfm
{
struct TwoViewOptions : public core::FieldTableOptions<TwoViewOptions>
{
	/** RANSAC iterations, each one draw of 8 correspondences shared by both models (the
	 * homography uses its first 4) (Default: 200) */
	int ransacIterations{200};
	/** RNG seed: the same seed and input give bit-identical results (Default: 2015) */
	uint64_t seed{2015};
	/** Keypoint position std at pyramid level 0 [px]; a correspondence's std in a view is this
	 * times its level scale (Default: 1 px) */
	double sigmaPx{1.0};
	/** Fewer correspondences are refused as TooFewMatches (Default: 100, as ORB-SLAM) */
	int minMatches{100};
	/** The chosen hypothesis's median parallax of its triangulated points must reach this
	 * [deg] (Default: 1 deg) */
	double minParallaxDeg{1.0};
	/** A point counts as triangulated (valid) only above this parallax [deg]: closer to 0 its
	 * depth is unconstrained (Default: 0.36 deg, cos = 0.99998 as ORB-SLAM) */
	double minPointParallaxDeg{0.36};
	/** The chosen hypothesis must triangulate at least this many points (Default: 50) */
	int minTriangulated{50};
	/** ... and pass the checks for at least this share of the model's inliers (Default: 0.9) */
	double minGoodShare{0.9};
	/** Ambiguous when the second-best hypothesis has more than this share of the best one's
	 * good points (Default: 0.75) */
	double maxSecondBestShare{0.75};
	/** A competing hypothesis whose median parallax is below min_parallax_deg and below this
	 * share of the best one's is no rival: it reads the views as nearly a rotation about a far
	 * scene, which could not start a map. This is the usual false solution of a plane seen
	 * under sideways motion: the homography's second decomposition puts the plane normal along
	 * the direction of travel, a plane seen edge-on whose points come out far away. Under
	 * forward motion both solutions keep comparable parallax and stay ambiguous. The parallax
	 * of both is compared after the best one's refinement. 0: every hypothesis with enough
	 * good points is a rival, as ORB-SLAM (Default: 0.5) */
	double rivalParallaxShare{0.5};
	/** ... and only when the best hypothesis turns the camera by at most this many times its
	 * median parallax: a view pair dominated by rotation has small errors of that rotation
	 * (rolling shutter, calibration) read as parallax (Default: 3) */
	double rivalMaxRotationRatio{3.0};
	/** The homography is chosen when R_H = S_H / (S_H + S_F) exceeds this (Default: 0.45, the
	 * paper; ORB-SLAM2's code uses 0.40) */
	double homographyRatio{0.45};
	/** The homography is also chosen when at least this share of F's inliers are H inliers:
	 * F is then degenerate. On a plane (or under pure rotation) F = H^-T [e]_x fits every pair
	 * for any epipole e, and as its residual has 1 dof against H's 2, S_F > S_H: R_H of an
	 * exact plane is 0.452 in expectation for exact models (0.41 with one view's sigma), and
	 * 0.44-0.45 measured, on the threshold (ORB-SLAM relies on its 8-point samples fitting a
	 * plane badly). Measured shares: plane and pure rotation 0.93-0.99, the general test
	 * scene 0.1-0.2 (Default: 0.8) */
	double homographyInlierShare{0.8};
	/** Score both models in parallel (std::async); the result does not depend on it
	 * (Default: true) */
	bool parallel{true};

	/** The INI keys, with description and rule (core/OptionFields.h). */
	core::OptionFields fields();
	/** Throws std::invalid_argument("[section] key = value (must be ...)") on a bad value. */
	void validate(const std::string& section = "two_view") const;
	/** validate() as a flag, its message in `error`. */
	bool isValid(std::string* error = nullptr) const;
};

/** Matched undistorted keypoints, correspondence i = (px_ref[i], px_cur[i]). Normalised image
 * coordinates work too with K = {1, 1, 0, 0} and sigmaPx in those units. */
struct TwoViewMatches
{
	std::vector<Eigen::Vector2d> px_ref, px_cur;
	/** Per-correspondence std factor (pyramid level scale, 1 at level 0) in each view; empty
	 * means 1 for all */
	std::vector<double> scale_ref, scale_cur;
};

enum class TwoViewModel
{
	None,
	Homography,
	Fundamental
};

enum class TwoViewFailure
{
	None,
	TooFewMatches,  //!< fewer correspondences than minMatches (or no model could be fitted)
	LowParallax,  //!< the chosen motion has too little parallax: pure rotation or tiny baseline
	Ambiguous,  //!< two motion hypotheses explain the inliers about equally well
	TooFewTriangulated  //!< the best hypothesis triangulates too few of the inliers
};

const char* toString(TwoViewFailure f);
const char* toString(TwoViewModel m);

/** A motion hypothesis that competed with the best one (TwoViewResult::candidates). */
struct TwoViewCandidate
{
	RelativeMotion motion;
	/** Per correspondence, as TwoViewResult::points_ref / triangulated */
	std::vector<Eigen::Vector3d> points_ref;
	std::vector<uint8_t> triangulated;
	int good{0};  //!< points passing cheirality and reprojection
	double parallaxDeg{0};  //!< median parallax of those [deg]
	/** Unit normal of the plane fitted to the triangulated points (reference frame, towards
	 * the camera): the plane a homography hypothesis implies */
	Eigen::Vector3d planeNormal_ref{Eigen::Vector3d::Zero()};
};

struct TwoViewResult
{
	bool ok{false};
	TwoViewFailure failure{TwoViewFailure::None};
	std::string message;  //!< why it failed (or what succeeded), with the numbers
	TwoViewModel model{TwoViewModel::None};  //!< the selected model (also on failure)
	/** X_cur = R_cur_ref X_ref + t_cur_ref; |t_cur_ref| = 1 (the map's scale is arbitrary) */
	RelativeMotion motion;
	/** Per correspondence: the point in the reference camera frame (scale of |t| = 1), valid
	 * when it passed cheirality, reprojection and the per-point parallax test */
	std::vector<Eigen::Vector3d> points_ref;
	std::vector<uint8_t> triangulated;
	/** Per correspondence: inlier of the selected model; on success re-gated on the refined
	 * motion (Sampson error at chi2(1) 95 %) */
	std::vector<uint8_t> inliers;
	Eigen::Matrix3d H_cur_ref{Eigen::Matrix3d::Zero()}, F_cur_ref{Eigen::Matrix3d::Zero()};
	double scoreH{0}, scoreF{0}, ratioH{0};
	/** Share of F's inliers that are also H inliers (see homographyInlierShare) */
	double sharedInlierShare{0};
	/** Median parallax of the selected hypothesis's good points [deg] */
	double parallaxDeg{0};
	int numInliers{0}, numTriangulated{0};
	/** Good points (cheirality + reprojection) of the best hypothesis and of its strongest
	 * rival (TwoViewOptions::rivalParallaxShare) */
	int bestGood{0}, secondGood{0};
	/** Failure Ambiguous: the hypotheses that explain the inliers about equally well, the best
	 * (refined) first. On a plane the homography's two motions both keep every point in front
	 * of the cameras; each implies another plane, and only the true plane stays the same from
	 * a second current frame (see Tracker: a later frame picks the motion whose plane
	 * normal agrees). */
	std::vector<TwoViewCandidate> candidates;
};

class TwoViewInitializer
{
   public:
	/** Throws std::invalid_argument when the options are invalid. */
	TwoViewInitializer(const PinholeIntrinsics& K, const TwoViewOptions& opts = {});

	/** Thread-safe (const, no state); throws std::invalid_argument on inconsistent sizes. */
	TwoViewResult initialize(const TwoViewMatches& matches) const;

	const TwoViewOptions& options() const { return m_opts; }

   private:
	PinholeIntrinsics m_K;
	TwoViewOptions m_opts;
};

}  // namespace keygrid::sfm
