#pragma once
/** \file LocalBundleAdjuster.h
 * Local bundle adjustment around a keyframe: the keyframe and its covisible neighbours and all
 * landmarks they see are optimised; keyframes that also see those landmarks stay fixed.
 * Huber loss, analytic Jacobians, Schur complement: Ceres (dense) for local windows, the
 * dedicated sparse solver of BundleLevenbergMarquardt.h for large problems.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>
#include <keygrid/sfm/PoseOptimizer.h>
#include <keygrid/sfm/SparseMap.h>

#include <memory>
#include <set>
#include <string>
#include <vector>

namespace keygrid::sfm
{
/** Linear solver of the Levenberg-Marquardt steps (all eliminate the landmarks first). */
enum class BaLinearSolver
{
	/** The dedicated sparse solver (BundleLevenbergMarquardt.h) for every problem with depth
	 * measurements and every problem of more than 60 optimised keyframes; Ceres' DenseSchur
	 * for a monocular window (no depth, at most 60 keyframes). With autodiff Jacobians
	 * (analytic_jacobians = false): Ceres' DenseSchur up to 60 keyframes, SparseSchur above */
	Auto,
	/** Ceres: dense Cholesky of the reduced camera system */
	DenseSchur,
	/** Ceres: SuiteSparse Cholesky of the reduced camera system */
	SparseSchur,
	/** Ceres: conjugate gradients on the reduced system, Schur-Jacobi preconditioner */
	IterativeSchur,
	/** The dedicated sparse solver for every problem, monocular windows included (analytic
	 * Jacobians whatever analytic_jacobians says) */
	Dedicated
};

struct BundleAdjusterOptions : public core::FieldTableOptions<BundleAdjusterOptions>
{
	/** Covisible keyframes optimised with the current one (Default: 10) */
	int windowSize{10};
	/** Fixed keyframes kept at most, the most covisible first (Default: 10) */
	int maxFixedKeyFrames{10};
	/** Levenberg-Marquardt iterations at most (Default: 10) */
	int iterations{10};
	/** Stop earlier once an iteration lowers the cost by less than this fraction (Ceres'
	 * function_tolerance; Default: 1e-6, Ceres' own). The local windows converge linearly
	 * (robust loss) and mostly run all `iterations`; a looser tolerance saves time at a cost in
	 * accuracy (doc/frontend.md, "Local mapping cost"). */
	double functionTolerance{1e-6};
	/** Chi-square outlier thresholds after the solve (Default: 5.991 / 7.815) */
	double chi2Mono{5.991}, chi2Rgbd{7.815};
	/** Virtual stereo baseline x fx for depth residuals (Default: 40) */
	double bf{40.0};
	/** Standard deviation of the virtual disparity bf / depth [px], level-independent
	 * (Default: 0.25; see PoseOptimizerOptions::disparitySigma) */
	double disparitySigma{0.25};
	/** Depth residuals only for depths below this [m] (Default: 6) */
	double maxDepthForRgbd{6.0};
	/** Threads used by the Ceres solvers (Default: 1; results are then deterministic). The
	 * dedicated solver of `auto` runs two threads whatever this says, with deterministic results. */
	int threads{1};
	/** Hand-written Jacobians (AnalyticReprojectionCost); false: Ceres autodiff of the
	 * templated costs (Default: true) */
	bool analyticJacobians{true};
	/** A landmark that no keyframe measured the depth of takes part only if two of its
	 * observing rays meet at this angle or more [deg]; otherwise it stays out of the problem
	 * (its depth is unobservable, see BundleAdjusterReport::landmarksLeftOut). 0: every landmark
	 * (Default: 0; the final global bundle adjustment uses [mapping] min_parallax_deg) */
	double minParallaxDegWithoutDepth{0};
	/** Linear solver, INI `linear_solver` = auto | dense_schur | sparse_schur |
	 * iterative_schur | dedicated (Default: auto) */
	BaLinearSolver linearSolver{BaLinearSolver::Auto};

	/** The bundle adjustment's keys (in [mapping]). */
	core::OptionFields fields();
	/** Throws std::invalid_argument naming section, key, value and rule of an invalid option. */
	void validate(const std::string& section = "mapping") const;
};

struct BundleAdjusterReport
{
	int keyframes{0}, fixedKeyFrames{0}, landmarks{0}, observations{0}, outliersRemoved{0};
	/** Landmarks seen by the moving keyframes but left out: no depth and too little parallax
	 * (BundleAdjusterOptions::minParallaxDegWithoutDepth); they keep their position */
	int landmarksLeftOut{0};
	/** Solved by the dedicated sparse solver (BundleLevenbergMarquardt.h), not by Ceres: the
	 * choice BundleAdjusterOptions::linearSolver made for this problem */
	bool dedicatedSolver{false};
	/** Levenberg-Marquardt iterations run (successful and rejected steps) */
	int iterations{0};
	double initialCost{0}, finalCost{0};
	/** Median over all observations of the squared normalised residual |r|^2 after the solve
	 * (outliers included, so the outlier gate does not bias it): a self-consistency measure
	 * of the camera model that needs no ground truth (2-3 for a consistent RGB-D model). */
	double medianChi2{0};
	/** Ceres' solve [s]: all of it, its residual and Jacobian evaluations, its linear solves */
	double solverSeconds{0}, evaluationSeconds{0}, linearSolverSeconds{0};
};

/** One bundle adjustment in three steps, so that threaded mode can solve without holding the
 * map lock: the constructor copies poses, points and measurements out of the map (lock held),
 * solve() touches only those copies, apply() writes the result back to whatever is still in
 * the map and drops the observations that remain outliers (lock held). */
class BundleAdjustment
{
   public:
	/** Keyframes `local` move, `fixed` ones only anchor; all landmarks seen by `local` move.
	 * The first keyframe of the map never moves (it defines the world frame). */
	BundleAdjustment(
		const SparseMap& map, const std::vector<KeyFrameId>& local, const std::set<KeyFrameId>& fixed,
		const PinholeIntrinsics& K, const BundleAdjusterOptions& opts);
	/** The local window of `kf`: it and its best covisibles move, the keyframes that share
	 * most of their landmarks stay fixed. */
	static BundleAdjustment around(
		const SparseMap& map, KeyFrameId kf, const PinholeIntrinsics& K, const BundleAdjusterOptions& opts);
	BundleAdjustment(BundleAdjustment&&) noexcept;
	~BundleAdjustment();

	void solve();
	BundleAdjusterReport apply(SparseMap& map);

   private:
	struct Problem;
	std::unique_ptr<Problem> m;
};

/** Optimises the window around `kf` in place and removes outlier observations. */
BundleAdjusterReport localBundleAdjustment(
	SparseMap& map, KeyFrameId kf, const PinholeIntrinsics& K, const BundleAdjusterOptions& opts);

/** Optimises every keyframe and landmark (the first keyframe fixed) and removes outliers. */
BundleAdjusterReport globalBundleAdjustment(
	SparseMap& map, const PinholeIntrinsics& K, const BundleAdjusterOptions& opts);

/** BundleAdjustment(map, local, fixed, ...) solved and applied. */
BundleAdjusterReport bundleAdjust(
	SparseMap& map, const std::vector<KeyFrameId>& local, const std::set<KeyFrameId>& fixed,
	const PinholeIntrinsics& K, const BundleAdjusterOptions& opts);

}  // namespace keygrid::sfm
