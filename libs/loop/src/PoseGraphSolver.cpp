#include "PoseGraphSolver.h"

#include <ceres/solver.h>
#include <ceres/types.h>

namespace keygrid::loop::detail
{
namespace
{
const PoseGraphOptions& validated(const PoseGraphOptions& opts)
{
	std::string why;
	if (!opts.isValid(&why)) throw std::invalid_argument("PoseGraphOptions: " + why);
	return opts;
}

std::unique_ptr<ceres::LossFunction> makeLoopLoss(const PoseGraphOptions& opts)
{
	if (opts.loopLoss == RobustLoss::Huber) return std::make_unique<ceres::HuberLoss>(opts.loopLossScale);
	if (opts.loopLoss == RobustLoss::Cauchy) return std::make_unique<ceres::CauchyLoss>(opts.loopLossScale);
	return nullptr;
}

ceres::Problem::Options problemOptions()
{
	ceres::Problem::Options po;
	po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
	po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
	return po;
}
}  // namespace

VertexBlocks::VertexBlocks(const Eigen::Vector3d& translation, const Eigen::Quaterniond& rotation, double logS)
	: logScale(logS)
{
	Eigen::Map<Eigen::Vector3d>(this->t) = translation;
	Eigen::Map<Eigen::Quaterniond>(this->q) = rotation.normalized();
}

GraphProblem::GraphProblem(const PoseGraphOptions& opts)
	: m_opts(validated(opts)), m_loopLoss(makeLoopLoss(opts)), m_problem(problemOptions())
{
}

void GraphProblem::addResidual(ceres::CostFunction* cost, EdgeKind kind, const std::vector<double*>& blocks)
{
	m_problem.AddResidualBlock(cost, kind == EdgeKind::Loop ? m_loopLoss.get() : nullptr, blocks);
}

void GraphProblem::holdScalesConstant()
{
	for (auto& [id, v] : m_vertices)
		if (m_problem.HasParameterBlock(&v.logScale)) m_problem.SetParameterBlockConstant(&v.logScale);
}

PoseGraphSolverReport GraphProblem::solve(const std::vector<KeyFrameId>& fixed)
{
	for (auto& [id, v] : m_vertices)
		if (m_problem.HasParameterBlock(v.q)) m_problem.SetManifold(v.q, &m_quaternionManifold);
	for (KeyFrameId id : fixed)
	{
		VertexBlocks& v = m_vertices.at(id);
		for (double* block : {v.t, v.q, &v.logScale})
			if (m_problem.HasParameterBlock(block)) m_problem.SetParameterBlockConstant(block);
	}

	ceres::Solver::Options so;
	so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
	if (ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE))
		so.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
	else
		so.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
	so.max_num_iterations = m_opts.maxIterations;
	so.function_tolerance = m_opts.functionTolerance;
	so.num_threads = m_opts.threads;
	so.logging_type = ceres::SILENT;
	ceres::Solver::Summary cs;
	if (m_problem.NumResidualBlocks() > 0) ceres::Solve(so, &m_problem, &cs);

	PoseGraphSolverReport rep;
	rep.usable = m_problem.NumResidualBlocks() == 0 || cs.IsSolutionUsable();
	rep.initialCost = cs.initial_cost;
	rep.finalCost = cs.final_cost;
	rep.iterations = static_cast<int>(cs.iterations.size());
	rep.seconds = cs.total_time_in_seconds;
	rep.linearSolver = std::string("SPARSE_NORMAL_CHOLESKY (") +
					   ceres::SparseLinearAlgebraLibraryTypeToString(so.sparse_linear_algebra_library_type) + ")";
	rep.message = cs.message;
	return rep;
}

}  // namespace keygrid::loop::detail
