#include <keygrid/sfm/LocalBundleAdjuster.h>
#include <mrpt/config/CConfigFileBase.h>

#include <ceres/ceres.h>
#include <algorithm>
#include <cmath>
#include <array>
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

/** Up to this many optimised keyframes the reduced camera system is solved densely. */
constexpr std::size_t kAutoDenseMaxKeyFrames = 60;

const char* solverName(BaLinearSolver s)
{
	switch (s)
	{
		case BaLinearSolver::DenseSchur: return "dense_schur";
		case BaLinearSolver::SparseSchur: return "sparse_schur";
		case BaLinearSolver::IterativeSchur: return "iterative_schur";
		default: return "auto";
	}
}
}  // namespace

void BundleAdjusterOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	windowSize = c.read_int(s, "window_size", windowSize);
	maxFixedKeyFrames = c.read_int(s, "max_fixed_keyframes", maxFixedKeyFrames);
	iterations = c.read_int(s, "iterations", iterations);
	functionTolerance = c.read_double(s, "function_tolerance", functionTolerance);
	threads = c.read_int(s, "threads", threads);
	analyticJacobians = c.read_bool(s, "analytic_jacobians", analyticJacobians);
	const std::string solver = c.read_string(s, "linear_solver", solverName(linearSolver));
	bool known = false;
	for (auto v : {BaLinearSolver::Auto, BaLinearSolver::DenseSchur, BaLinearSolver::SparseSchur, BaLinearSolver::IterativeSchur})
		if (solver == solverName(v))
		{
			linearSolver = v;
			known = true;
		}
	if (!known)
		throw std::invalid_argument("[" + s + "] linear_solver = " + solver + " (must be auto, dense_schur, sparse_schur or iterative_schur)");
	if (windowSize < 1) throw std::invalid_argument("[" + s + "] window_size = " + std::to_string(windowSize) + " (must be >= 1)");
	if (iterations < 1) throw std::invalid_argument("[" + s + "] iterations = " + std::to_string(iterations) + " (must be >= 1)");
	if (!(functionTolerance >= 0 && functionTolerance < 1))
		throw std::invalid_argument("[" + s + "] function_tolerance = " + std::to_string(functionTolerance) + " (must be in [0, 1))");
	if (threads < 1) throw std::invalid_argument("[" + s + "] threads = " + std::to_string(threads) + " (must be >= 1)");
}

void BundleAdjusterOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	c.write(s, "window_size", windowSize, 30, 40, "covisible keyframes optimised with the new one");
	c.write(s, "max_fixed_keyframes", maxFixedKeyFrames, 30, 40, "fixed keyframes anchoring the window");
	c.write(s, "iterations", iterations, 30, 40, "Levenberg-Marquardt iterations at most");
	c.write(s, "function_tolerance", functionTolerance, 30, 40, "stop once an iteration lowers the cost by less than this fraction");
	c.write(s, "threads", threads, 30, 40, "Ceres threads (1 = deterministic)");
	c.write(s, "analytic_jacobians", analyticJacobians, 30, 40, "hand-written Jacobians (false: Ceres autodiff)");
	c.write(s, "linear_solver", std::string(solverName(linearSolver)), 30, 40, "auto | dense_schur | sparse_schur | iterative_schur");
}

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
	struct Obs
	{
		LandmarkId lm;
		KeyFrameId kf;
		bool rgbd;
		ceres::ResidualBlockId block;
	};
	BundleAdjusterOptions opts;
	std::vector<KeyFrameId> local;
	std::map<KeyFrameId, std::size_t> poseIndex;  // keyframe -> row of poses
	std::vector<std::array<double, 7>> poses;  // q(x,y,z,w), t of T_cam_world
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
	explicit Problem(const BundleAdjusterOptions& o)
		: opts(o), lossMono(std::sqrt(o.chi2Mono)), lossRgbd(std::sqrt(o.chi2Rgbd)), problem(problemOptions())
	{
	}
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
	: m(std::make_unique<Problem>(o))
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

	auto& problem = m->problem;
	// Schur ordering given explicitly (landmarks eliminated first, then poses), which spares
	// Ceres the independent-set search over the problem graph.
	for (const auto& [id, i] : m->poseIndex)
	{
		auto& pq = m->poses[i];
		problem.AddParameterBlock(pq.data(), 4, new ceres::EigenQuaternionManifold());
		problem.AddParameterBlock(pq.data() + 4, 3);
		m->ordering->AddElementToGroup(pq.data(), 1);
		m->ordering->AddElementToGroup(pq.data() + 4, 1);
		// Gauge: keyframe 0 defines the world frame and never moves; fixed observers anchor
		// the window to the rest of the map.
		if (fixedSet.count(id) || id == map.keyframes().begin()->first)
		{
			problem.SetParameterBlockConstant(pq.data());
			problem.SetParameterBlockConstant(pq.data() + 4);
		}
	}
	auto& all = m->all;
	for (std::size_t lmRow = 0; lmRow < m->lms.size(); lmRow++)
	{
		const LandmarkId lm = m->lms[lmRow];
		double* point = m->points[lmRow].data();
		for (const auto& [kf, kp] : map.landmark(lm).observations)
		{
			const auto pi = m->poseIndex.find(kf);
			if (pi == m->poseIndex.end()) continue;
			auto& pq = m->poses[pi->second];
			double u, v, ur;
			if (!projectRgbd(pq.data(), pq.data() + 4, static_cast<const double*>(point), K, 0.0, u, v, ur))
			{
				m->behind.emplace_back(lm, kf);
				continue;
			}
			const auto& f = map.keyframe(kf).features;
			const Eigen::Vector2d uv(f.undistorted[kp].x, f.undistorted[kp].y);
			const double invSigma = 1.0 / f.levelScale[f.keypoints[kp].octave];
			const double d = f.depth[kp];
			const bool rgbd = d > 0 && d < o.maxDepthForRgbd;
			ceres::CostFunction* cost = nullptr;
			if (o.analyticJacobians)
				cost = new AnalyticBaCost(AnalyticReprojectionCost(uv, rgbd ? d : 0.0, o.bf, invSigma, 1.0 / o.disparitySigma, K));
			else if (rgbd)
				cost = new ceres::AutoDiffCostFunction<RgbdReprojectionCost, 3, 4, 3, 3>(
					new RgbdReprojectionCost(uv, d, o.bf, invSigma, 1.0 / o.disparitySigma, K));
			else
				cost = new ceres::AutoDiffCostFunction<MonoReprojectionCost, 2, 4, 3, 3>(new MonoReprojectionCost(uv, invSigma, K));
			const auto block = problem.AddResidualBlock(
				cost, rgbd ? &m->lossRgbd : &m->lossMono, pq.data(), pq.data() + 4, point);
			if (all.empty() || all.back().lm != lm) m->ordering->AddElementToGroup(point, 0);
			all.push_back({lm, kf, rgbd, block});
		}
	}
	rep.keyframes = static_cast<int>(local.size());
	rep.fixedKeyFrames = static_cast<int>(fixedSet.size());
	rep.landmarks = static_cast<int>(m->lms.size());
	rep.observations = static_cast<int>(all.size());
}

BundleAdjustment::BundleAdjustment(BundleAdjustment&&) noexcept = default;
BundleAdjustment::~BundleAdjustment() = default;

void BundleAdjustment::solve()
{
	if (m->all.empty()) return;
	const auto& o = m->opts;
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
			// fastest for local windows, sparse for large (global) problems.
			so.linear_solver_type = m->local.size() <= kAutoDenseMaxKeyFrames ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
	}
	so.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
	so.linear_solver_ordering = m->ordering;
	so.max_num_iterations = o.iterations;
	so.function_tolerance = o.functionTolerance;
	so.num_threads = o.threads;
	so.logging_type = ceres::SILENT;
	ceres::Solver::Summary summary;
	ceres::Solve(so, &m->problem, &summary);
	m->report.initialCost = summary.initial_cost;
	m->report.finalCost = summary.final_cost;
	m->report.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
	m->report.solverSeconds = summary.total_time_in_seconds;
	m->report.evaluationSeconds = summary.residual_evaluation_time_in_seconds + summary.jacobian_evaluation_time_in_seconds;
	m->report.linearSolverSeconds = summary.linear_solver_time_in_seconds;
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
	for (const auto& ob : m->all)
	{
		double cost = 0;
		m->problem.EvaluateResidualBlock(ob.block, false, &cost, nullptr, nullptr);
		// EvaluateResidualBlock(apply_loss_function=false) gives 0.5 |r|^2.
		chi2.push_back(2.0 * cost);
		if (2.0 * cost > (ob.rgbd ? o.chi2Rgbd : o.chi2Mono) && map.hasLandmark(ob.lm))
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
