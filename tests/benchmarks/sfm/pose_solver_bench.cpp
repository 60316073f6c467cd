// One inner solve of optimizePose (10 Levenberg-Marquardt iterations, Huber loss, from a pose
// a few cm and degrees off) on N observations: the dedicated solver beside Ceres, which
// optimizePose used before, with the same analytic residual (AnalyticReprojectionCost) and a
// problem built per solve as it did.
//
//   build/bin/keygrid_pose_solver_bench [--benchmark_repetitions=5 --benchmark_report_aggregates_only=true]
#include <benchmark/benchmark.h>

#include "CeresPoseReference.h"

using namespace keygrid::sfm;
using namespace keygrid::sfm::test;

namespace
{
constexpr int kIterations = 10;

/** AnalyticReprojectionCost with the point held constant, as a Ceres cost function. */
class AnalyticPoseCost final : public ceres::SizedCostFunction<3, 4, 3>
{
   public:
	explicit AnalyticPoseCost(const PoseResidualTerm& term)
		: m_cost(term.uv, term.disparity > 0 ? kBf / term.disparity : 0.0, kBf, term.invSigma, term.invSigmaDisparity, K),
		  m_p(term.p_world)
	{
	}
	bool Evaluate(double const* const* x, double* r, double** J) const override
	{
		return m_cost.evaluate(x[0], x[1], m_p.data(), r, J ? J[0] : nullptr, J ? J[1] : nullptr, nullptr);
	}

   private:
	AnalyticReprojectionCost m_cost;
	Eigen::Vector3d m_p;
};

Problem startProblem(int n, Eigen::Matrix3d& R, Eigen::Vector3d& t)
{
	auto p = makeProblem(n, 0.7, n / 10, std::sqrt(5.991), 7);
	R = Eigen::AngleAxisd(0.05, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix() * p.R;
	t = p.t + Eigen::Vector3d(0.04, -0.03, 0.05);
	return p;
}

void BM_DedicatedSolver(benchmark::State& state)
{
	Eigen::Matrix3d R0;
	Eigen::Vector3d t0;
	const auto p = startProblem(static_cast<int>(state.range(0)), R0, t0);
	PoseSolverOptions o;
	o.maxIterations = kIterations;
	for (auto _ : state)
	{
		Eigen::Matrix3d R = R0;
		Eigen::Vector3d t = t0;
		benchmark::DoNotOptimize(solvePoseLevenbergMarquardt(R, t, p.terms, K, kBf, o).finalCost);
	}
}

void BM_Ceres(benchmark::State& state)
{
	Eigen::Matrix3d R0;
	Eigen::Vector3d t0;
	const auto p = startProblem(static_cast<int>(state.range(0)), R0, t0);
	ceres::HuberLoss huber(std::sqrt(5.991));
	for (auto _ : state)
	{
		const Eigen::Quaterniond qe(R0);
		double q[4] = {qe.x(), qe.y(), qe.z(), qe.w()}, tv[3] = {t0.x(), t0.y(), t0.z()};
		ceres::Problem::Options po;
		po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
		ceres::Problem problem(po);
		problem.AddParameterBlock(q, 4, new ceres::EigenQuaternionManifold());
		problem.AddParameterBlock(tv, 3);
		for (const auto& term : p.terms) problem.AddResidualBlock(new AnalyticPoseCost(term), &huber, q, tv);
		ceres::Solver::Options so;
		so.linear_solver_type = ceres::DENSE_QR;
		so.max_num_iterations = kIterations;
		so.num_threads = 1;
		so.logging_type = ceres::SILENT;
		ceres::Solver::Summary summary;
		ceres::Solve(so, &problem, &summary);
		benchmark::DoNotOptimize(summary.final_cost);
	}
}
}  // namespace

BENCHMARK(BM_DedicatedSolver)->Arg(100)->Arg(300)->Arg(1000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Ceres)->Arg(100)->Arg(300)->Arg(1000)->Unit(benchmark::kMicrosecond);
