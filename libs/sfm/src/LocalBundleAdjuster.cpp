#include <keygrid/sfm/BundleLevenbergMarquardt.h>
#include <keygrid/sfm/LocalBundleAdjuster.h>
#include <mrpt/config/CConfigFileBase.h>

#include <ceres/ceres.h>
#include <algorithm>
#include <cmath>
#include <array>
#include <chrono>
#include <limits>
#include <set>

namespace keygrid::sfm
{
namespace
{
/** Ceres wrapper of AnalyticReprojectionCost (3 residuals; q_cam_world[4], t_cam_world[3],
 * p_world[3]). */
class AnalyticBaCost final : public ceres::SizedCostFunction<3, 4, 3, 3>
{
   public:
	explicit AnalyticBaCost(const AnalyticReprojectionCost& c) : m_cost(c) {}
	bool Evaluate(double const* const* x, double* r, double** J) const override
	{
		return m_cost.evaluate(x[0], x[1], x[2], r, J ? J[0] : nullptr, J ? J[1] : nullptr, J ? J[2] : nullptr);
	}

   private:
	AnalyticReprojectionCost m_cost;
};

/** Up to this many optimised keyframes, `linear_solver = auto` leaves a problem without depth
 * measurements to Ceres' dense Schur (and with autodiff Jacobians, any problem). */
constexpr std::size_t kAutoDenseMaxKeyFrames = 60;

/** `linear_solver = auto` with analytic Jacobians: the dedicated sparse solver
 * (BundleLevenbergMarquardt.h) for every problem with depth measurements, local windows
 * included, and for every problem of more than kAutoDenseMaxKeyFrames moving keyframes. It
 * reaches the optimum Ceres' Schur solvers reach, without their problem building and
 * preprocessing, which dominate on a local window. A monocular window (no depth) keeps Ceres'
 * dense Schur: with the dedicated solver, monocular runs of a validation scene ended off in
 * scale more often, though window by window both solvers reach the same optimum (doc/frontend.md,
 * "Local mapping cost"): not adopted until more runs say whether that was chance. */
bool usesDedicatedSolver(const BundleAdjusterOptions& o, std::size_t movingKeyFrames, bool depthMeasured)
{
	if (o.linearSolver == BaLinearSolver::Dedicated) return true;
	return o.linearSolver == BaLinearSolver::Auto && o.analyticJacobians && (depthMeasured || movingKeyFrames > kAutoDenseMaxKeyFrames);
}

const char* solverName(BaLinearSolver s)
{
	switch (s)
	{
		case BaLinearSolver::DenseSchur: return "dense_schur";
		case BaLinearSolver::SparseSchur: return "sparse_schur";
		case BaLinearSolver::IterativeSchur: return "iterative_schur";
		case BaLinearSolver::Dedicated: return "dedicated";
		default: return "auto";
	}
}
}  // namespace

core::OptionFields BundleAdjusterOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("window_size", windowSize, "covisible keyframes optimised with the new one", R::atLeast(1));
	f.add("max_fixed_keyframes", maxFixedKeyFrames, "fixed keyframes anchoring the window");
	f.add("iterations", iterations, "Levenberg-Marquardt iterations at most", R::atLeast(1));
	f.add("function_tolerance", functionTolerance, "stop once an iteration lowers the cost by less than this fraction", R::fromBelow(0, 1));
	f.add("threads", threads, "threads of the Ceres solvers (1 = deterministic; auto's dedicated solver always runs two, deterministically)", R::atLeast(1));
	f.add("analytic_jacobians", analyticJacobians, "hand-written Jacobians (false: Ceres autodiff)");
	f.addCustom(
		"linear_solver",
		{[this](const std::string& text) {
			 for (auto v : {BaLinearSolver::Auto, BaLinearSolver::DenseSchur, BaLinearSolver::SparseSchur, BaLinearSolver::IterativeSchur,
						   BaLinearSolver::Dedicated})
				 if (text == solverName(v))
				 {
					 linearSolver = v;
					 return;
				 }
			 throw std::invalid_argument("expected auto, dense_schur, sparse_schur, iterative_schur or dedicated");
		 },
		 [this] { return std::string(solverName(linearSolver)); }},
		"linear solver: auto (keygrid's dedicated sparse Schur; Ceres' dense Schur for monocular windows) | dense_schur | sparse_schur | iterative_schur (Ceres) | dedicated (keygrid's, every problem)");
	return f;
}

void BundleAdjusterOptions::validate(const std::string& s) const { core::validateFields(*this, s); }

BundleAdjustment BundleAdjustment::around(
	const SparseMap& map, KeyFrameId kfId, const PinholeIntrinsics& K, const BundleAdjusterOptions& o)
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
	return BundleAdjustment(map, local, fixedSet, K, o);
}

BundleAdjusterReport localBundleAdjustment(
	SparseMap& map, KeyFrameId kfId, const PinholeIntrinsics& K, const BundleAdjusterOptions& o)
{
	auto ba = BundleAdjustment::around(map, kfId, K, o);
	ba.solve();
	return ba.apply(map);
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
	BundleAdjustment ba(map, local, fixedSet, K, o);
	ba.solve();
	return ba.apply(map);
}

/** The problem owns copies of the parameters; the cost functions own their measurements. */
struct BundleAdjustment::Problem
{
	/** One observation: who, the measurement, and where it is in the problem. */
	struct Obs
	{
		LandmarkId lm;
		KeyFrameId kf;
		bool rgbd;
		Eigen::Vector2d uv;  // undistorted pixel
		double depth;  // measured depth (used when rgbd)
		double invSigma;  // 1 / sigma of the keypoint's level
		std::size_t pose, point;  // rows of poses and points
		ceres::ResidualBlockId block{nullptr};  // Ceres' residual block (Ceres solves only)
	};
	BundleAdjusterOptions opts;
	PinholeIntrinsics K;
	/** Solved by solveBundleLevenbergMarquardt instead of Ceres (see usesDedicatedSolver). */
	bool dedicated{false};
	std::vector<KeyFrameId> local;
	std::map<KeyFrameId, std::size_t> poseIndex;  // keyframe -> row of poses
	std::vector<std::array<double, 7>> poses;  // q(x,y,z,w), t of T_cam_world
	std::vector<char> constant;  // per pose row: a fixed observer or the map's first keyframe
	std::vector<LandmarkId> lms;  // in id order
	std::vector<std::array<double, 3>> points;  // in the order of lms
	std::vector<Obs> all;
	/** Observations whose point starts behind (or at) its camera: left out of the problem
	 * (one residual that cannot be evaluated at the start makes Ceres abandon the whole
	 * solve) and removed as outliers by apply(). */
	std::vector<std::pair<LandmarkId, KeyFrameId>> behind;
	ceres::HuberLoss lossMono, lossRgbd;
	std::shared_ptr<ceres::ParameterBlockOrdering> ordering = std::make_shared<ceres::ParameterBlockOrdering>();
	ceres::Problem problem;
	BundleAdjusterReport report;

	static ceres::Problem::Options problemOptions()
	{
		ceres::Problem::Options po;
		po.manifold_ownership = ceres::TAKE_OWNERSHIP;
		// One robust loss per kind of observation, shared by all residual blocks.
		po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
		return po;
	}
	Problem(const BundleAdjusterOptions& o, const PinholeIntrinsics& K_)
		: opts(o), K(K_), lossMono(std::sqrt(o.chi2Mono)), lossRgbd(std::sqrt(o.chi2Rgbd)), problem(problemOptions())
	{
	}

	void buildCeresProblem();
	void solveWithCeres();
	void solveDedicated();
	/** 2 x the unrobustified cost of observation k at the solved parameters: |r|^2. */
	double squaredResidual(std::size_t k) const;
};

namespace
{
/** Whether a landmark's position is observable from its observations: some keyframe measured
 * its depth, or two observing rays meet at `minParallaxDegWithoutDepth` or more. Along the ray
 * of an unobservable one the problem is (nearly) singular: a Gauss-Newton step can throw the
 * point behind a camera, where its residual cannot be evaluated, and Ceres then rejects the
 * whole step and shrinks its trust region; on a long loop that turned a few such points into
 * dozens of wasted iterations. */
bool depthObservable(const SparseMap& map, LandmarkId id, const BundleAdjusterOptions& o)
{
	if (o.minParallaxDegWithoutDepth <= 0) return true;
	const auto& lm = map.landmark(id);
	std::vector<Eigen::Vector3d> rays;
	for (const auto& [kf, kp] : lm.observations)
	{
		const auto& k = map.keyframe(kf);
		const float d = k.features.depth[kp];
		if (d > 0 && d < o.maxDepthForRgbd) return true;
		const auto c = k.T_world_cam.translation();
		rays.push_back((lm.p_world - Eigen::Vector3d(c.x, c.y, c.z)).normalized());
	}
	const double cosMin = std::cos(o.minParallaxDegWithoutDepth * M_PI / 180.0);
	for (std::size_t a = 0; a < rays.size(); a++)
		for (std::size_t b = a + 1; b < rays.size(); b++)
			if (rays[a].dot(rays[b]) <= cosMin) return true;
	return false;
}
}  // namespace

BundleAdjustment::BundleAdjustment(
	const SparseMap& map, const std::vector<KeyFrameId>& local, const std::set<KeyFrameId>& fixedSet,
	const PinholeIntrinsics& K, const BundleAdjusterOptions& o)
	: m(std::make_unique<Problem>(o, K))
{
	m->local = local;
	auto& rep = m->report;
	if (local.empty()) return;
	std::set<LandmarkId> lmSet;
	std::set<LandmarkId> leftOut;
	for (KeyFrameId id : local)
		for (LandmarkId lm : map.keyframe(id).landmarks)
			if (lm != kNoLandmark && map.hasLandmark(lm) && !lmSet.count(lm) && !leftOut.count(lm))
				(depthObservable(map, lm, o) ? lmSet : leftOut).insert(lm);
	m->lms.assign(lmSet.begin(), lmSet.end());
	rep.landmarksLeftOut = static_cast<int>(leftOut.size());

	// --- Parameter blocks.
	// Parameters live in two contiguous arrays in id order. Ceres orders the blocks of one
	// elimination group by address, so this keeps the solve (and the trajectory) bit-identical
	// from run to run.
	for (KeyFrameId id : local) m->poseIndex.emplace(id, 0);
	for (KeyFrameId id : fixedSet) m->poseIndex.emplace(id, 0);
	m->poses.resize(m->poseIndex.size());
	std::size_t row = 0;
	for (auto& [id, i] : m->poseIndex)
	{
		i = row++;
		toCeres(map.keyframe(id).T_world_cam, m->poses[i].data(), m->poses[i].data() + 4);
	}
	m->points.reserve(m->lms.size());
	for (LandmarkId lm : m->lms)
	{
		const auto& p = map.landmark(lm).p_world;
		m->points.push_back({p.x(), p.y(), p.z()});
	}

	m->constant.assign(m->poses.size(), 0);
	for (const auto& [id, i] : m->poseIndex)
		// Gauge: keyframe 0 defines the world frame and never moves; fixed observers anchor
		// the window to the rest of the map.
		m->constant[i] = fixedSet.count(id) || id == map.keyframes().begin()->first;
	auto& all = m->all;
	// At most one entry per observation of the landmarks: reserved at once (a global
	// adjustment holds hundreds of thousands, and a doubling vector up to twice that).
	std::size_t observations = 0;
	for (LandmarkId lm : m->lms) observations += map.landmark(lm).observations.size();
	all.reserve(observations);
	for (std::size_t lmRow = 0; lmRow < m->lms.size(); lmRow++)
	{
		const LandmarkId lm = m->lms[lmRow];
		const double* point = m->points[lmRow].data();
		for (const auto& [kf, kp] : map.landmark(lm).observations)
		{
			const auto pi = m->poseIndex.find(kf);
			if (pi == m->poseIndex.end()) continue;
			const auto& pq = m->poses[pi->second];
			double u, v, ur;
			if (!projectRgbd(pq.data(), pq.data() + 4, point, K, 0.0, u, v, ur))
			{
				m->behind.emplace_back(lm, kf);
				continue;
			}
			const auto& f = map.keyframe(kf).features;
			const double d = f.depth[kp];
			all.push_back({lm, kf, d > 0 && d < o.maxDepthForRgbd, Eigen::Vector2d(f.undistorted[kp].x, f.undistorted[kp].y), d,
				1.0 / f.levelScale[f.keypoints[kp].octave], pi->second, lmRow});
		}
	}
	const bool depthMeasured = std::any_of(all.begin(), all.end(), [](const Problem::Obs& ob) { return ob.rgbd; });
	m->dedicated = usesDedicatedSolver(o, local.size(), depthMeasured);
	if (!m->dedicated) m->buildCeresProblem();
	rep.dedicatedSolver = m->dedicated;
	rep.keyframes = static_cast<int>(local.size());
	rep.fixedKeyFrames = static_cast<int>(fixedSet.size());
	rep.landmarks = static_cast<int>(m->lms.size());
	rep.observations = static_cast<int>(all.size());
}

void BundleAdjustment::Problem::buildCeresProblem()
{
	// Schur ordering given explicitly (landmarks eliminated first, then poses), which spares
	// Ceres the independent-set search over the problem graph.
	for (const auto& [id, i] : poseIndex)
	{
		auto& pq = poses[i];
		problem.AddParameterBlock(pq.data(), 4, new ceres::EigenQuaternionManifold());
		problem.AddParameterBlock(pq.data() + 4, 3);
		ordering->AddElementToGroup(pq.data(), 1);
		ordering->AddElementToGroup(pq.data() + 4, 1);
		if (constant[i])
		{
			problem.SetParameterBlockConstant(pq.data());
			problem.SetParameterBlockConstant(pq.data() + 4);
		}
	}
	const auto& o = opts;
	for (std::size_t k = 0; k < all.size(); k++)
	{
		auto& ob = all[k];
		auto& pq = poses[ob.pose];
		double* point = points[ob.point].data();
		ceres::CostFunction* cost = nullptr;
		if (o.analyticJacobians)
			cost = new AnalyticBaCost(AnalyticReprojectionCost(ob.uv, ob.rgbd ? ob.depth : 0.0, o.bf, ob.invSigma, 1.0 / o.disparitySigma, K));
		else if (ob.rgbd)
			cost = new ceres::AutoDiffCostFunction<RgbdReprojectionCost, 3, 4, 3, 3>(
				new RgbdReprojectionCost(ob.uv, ob.depth, o.bf, ob.invSigma, 1.0 / o.disparitySigma, K));
		else
			cost = new ceres::AutoDiffCostFunction<MonoReprojectionCost, 2, 4, 3, 3>(new MonoReprojectionCost(ob.uv, ob.invSigma, K));
		ob.block = problem.AddResidualBlock(cost, ob.rgbd ? &lossRgbd : &lossMono, pq.data(), pq.data() + 4, point);
		if (k == 0 || all[k - 1].lm != ob.lm) ordering->AddElementToGroup(point, 0);
	}
}

BundleAdjustment::BundleAdjustment(BundleAdjustment&&) noexcept = default;
BundleAdjustment::~BundleAdjustment() = default;

void BundleAdjustment::solve()
{
	if (m->all.empty()) return;
	if (m->dedicated)
		m->solveDedicated();
	else
		m->solveWithCeres();
}

void BundleAdjustment::Problem::solveWithCeres()
{
	const auto& o = opts;
	ceres::Solver::Options so;
	switch (o.linearSolver)
	{
		case BaLinearSolver::DenseSchur: so.linear_solver_type = ceres::DENSE_SCHUR; break;
		case BaLinearSolver::SparseSchur: so.linear_solver_type = ceres::SPARSE_SCHUR; break;
		case BaLinearSolver::IterativeSchur:
			so.linear_solver_type = ceres::ITERATIVE_SCHUR;
			so.preconditioner_type = ceres::SCHUR_JACOBI;
			break;
		default:
			// The reduced camera system has 6 unknowns per moving keyframe: dense Cholesky is the
			// fastest for local windows, sparse for large problems (autodiff Jacobians).
			so.linear_solver_type = local.size() <= kAutoDenseMaxKeyFrames ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
	}
	so.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
	so.linear_solver_ordering = ordering;
	so.max_num_iterations = o.iterations;
	so.function_tolerance = o.functionTolerance;
	so.num_threads = o.threads;
	so.logging_type = ceres::SILENT;
	ceres::Solver::Summary summary;
	ceres::Solve(so, &problem, &summary);
	report.initialCost = summary.initial_cost;
	report.finalCost = summary.final_cost;
	report.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
	report.solverSeconds = summary.total_time_in_seconds;
	report.evaluationSeconds = summary.residual_evaluation_time_in_seconds + summary.jacobian_evaluation_time_in_seconds;
	report.linearSolverSeconds = summary.linear_solver_time_in_seconds;
}

void BundleAdjustment::Problem::solveDedicated()
{
	const auto t0 = std::chrono::steady_clock::now();
	const auto& o = opts;
	std::vector<BundleCamera> cameras(poses.size());
	for (std::size_t i = 0; i < poses.size(); i++)
	{
		const auto& pq = poses[i];
		cameras[i].R_cam_world = Eigen::Quaterniond(pq[3], pq[0], pq[1], pq[2]).normalized().toRotationMatrix();
		cameras[i].t_cam_world = Eigen::Vector3d(pq[4], pq[5], pq[6]);
		cameras[i].fixed = constant[i] != 0;
	}
	std::vector<Eigen::Vector3d> xyz(points.size());
	for (std::size_t j = 0; j < points.size(); j++) xyz[j] = Eigen::Vector3d(points[j][0], points[j][1], points[j][2]);
	std::vector<BundleTerm> terms(all.size());
	for (std::size_t k = 0; k < all.size(); k++)
	{
		const auto& ob = all[k];
		auto& t = terms[k];
		t.camera = static_cast<int>(ob.pose);
		t.point = static_cast<int>(ob.point);
		t.uv = ob.uv;
		t.invSigma = ob.invSigma;
		t.disparity = ob.rgbd ? o.bf / ob.depth : 0.0;
		t.invSigmaDisparity = 1.0 / o.disparitySigma;
		t.huberDelta = std::sqrt(ob.rgbd ? o.chi2Rgbd : o.chi2Mono);
	}
	BundleSolverOptions so;
	so.maxIterations = o.iterations;
	so.functionTolerance = o.functionTolerance;
	const auto s = solveBundleLevenbergMarquardt(cameras, xyz, terms, K, o.bf, so);
	for (std::size_t i = 0; i < poses.size(); i++)
	{
		if (constant[i]) continue;
		const Eigen::Quaterniond q = Eigen::Quaterniond(cameras[i].R_cam_world).normalized();
		poses[i] = {q.x(), q.y(), q.z(), q.w(), cameras[i].t_cam_world.x(), cameras[i].t_cam_world.y(), cameras[i].t_cam_world.z()};
	}
	for (std::size_t j = 0; j < points.size(); j++) points[j] = {xyz[j].x(), xyz[j].y(), xyz[j].z()};
	report.initialCost = s.initialCost;
	report.finalCost = s.finalCost;
	report.iterations = s.iterations;
	report.evaluationSeconds = s.evaluationSeconds;
	report.linearSolverSeconds = s.linearSolverSeconds;
	report.solverSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double BundleAdjustment::Problem::squaredResidual(std::size_t k) const
{
	const auto& ob = all[k];
	if (ob.block)
	{
		double cost = 0;
		problem.EvaluateResidualBlock(ob.block, false, &cost, nullptr, nullptr);
		// EvaluateResidualBlock(apply_loss_function=false) gives 0.5 |r|^2.
		return 2.0 * cost;
	}
	const auto& pq = poses[ob.pose];
	const AnalyticReprojectionCost c(ob.uv, ob.rgbd ? ob.depth : 0.0, opts.bf, ob.invSigma, 1.0 / opts.disparitySigma, K);
	double r[3];
	if (!c.evaluate(pq.data(), pq.data() + 4, points[ob.point].data(), r, nullptr, nullptr, nullptr))
		return std::numeric_limits<double>::infinity();
	return r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
}

BundleAdjusterReport BundleAdjustment::apply(SparseMap& map)
{
	auto rep = m->report;
	if (m->all.empty()) return rep;
	// --- Write back what is still in the map (in threaded mode tracking may have erased
	// landmarks meanwhile), then drop observations that remain outliers (plain chi-square).
	for (KeyFrameId id : m->local)
		if (map.hasKeyFrame(id))
		{
			const auto& pq = m->poses[m->poseIndex.at(id)];
			map.keyframe(id).T_world_cam = fromCeres(pq.data(), pq.data() + 4);
		}
	for (std::size_t i = 0; i < m->lms.size(); i++)
		if (map.hasLandmark(m->lms[i]))
		{
			const auto& p = m->points[i];
			map.landmark(m->lms[i]).p_world = Eigen::Vector3d(p[0], p[1], p[2]);
		}
	const auto& o = m->opts;
	for (const auto& [lm, kf] : m->behind)
		if (map.hasLandmark(lm) && map.landmark(lm).observations.count(kf))
		{
			map.eraseObservation(lm, kf);
			rep.outliersRemoved++;
		}
	std::vector<double> chi2;
	chi2.reserve(m->all.size());
	for (std::size_t k = 0; k < m->all.size(); k++)
	{
		const auto& ob = m->all[k];
		chi2.push_back(m->squaredResidual(k));
		if (chi2.back() > (ob.rgbd ? o.chi2Rgbd : o.chi2Mono) && map.hasLandmark(ob.lm))
		{
			map.eraseObservation(ob.lm, ob.kf);
			rep.outliersRemoved++;
		}
	}
	const auto mid = chi2.begin() + static_cast<std::ptrdiff_t>(chi2.size() / 2);
	std::nth_element(chi2.begin(), mid, chi2.end());
	rep.medianChi2 = *mid;
	for (LandmarkId lm : m->lms)
		if (map.hasLandmark(lm)) map.updateLandmarkStats(lm);
	return rep;
}

}  // namespace keygrid::sfm
