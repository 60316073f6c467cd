#include <ceres/ceres.h>
#include <keygrid/loop/PoseGraph.h>
#include <keygrid/loop/RelativePoseError.h>
#include <mrpt/config/CConfigFileBase.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <memory>
#include <stdexcept>

namespace keygrid::loop
{
bool PoseGraphOptions::isValid(std::string* why) const
{
	auto fail = [&](const std::string& s) {
		if (why) *why = s;
		return false;
	};
	if (!(loopLossScale > 0)) return fail("loop_loss_scale = " + std::to_string(loopLossScale) + " (must be > 0)");
	if (maxIterations < 1) return fail("max_iterations = " + std::to_string(maxIterations) + " (must be >= 1)");
	if (!(functionTolerance > 0)) return fail("function_tolerance = " + std::to_string(functionTolerance) + " (must be > 0)");
	if (threads < 1) return fail("threads = " + std::to_string(threads) + " (must be >= 1)");
	return true;
}

void PoseGraphOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	const std::string loss = c.read_string(s, "loop_loss", loopLoss == RobustLoss::None ? "none" : loopLoss == RobustLoss::Huber ? "huber" : "cauchy");
	if (loss == "none") loopLoss = RobustLoss::None;
	else if (loss == "huber") loopLoss = RobustLoss::Huber;
	else if (loss == "cauchy") loopLoss = RobustLoss::Cauchy;
	else throw std::invalid_argument("[" + s + "] loop_loss = " + loss + " (must be none, huber or cauchy)");
	loopLossScale = c.read_double(s, "loop_loss_scale", loopLossScale);
	maxIterations = c.read_int(s, "max_iterations", maxIterations);
	functionTolerance = c.read_double(s, "function_tolerance", functionTolerance);
	threads = c.read_int(s, "threads", threads);
	std::string why;
	if (!isValid(&why)) throw std::invalid_argument("[" + s + "] " + why);
}

void PoseGraphOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	c.write(s, "loop_loss", std::string(loopLoss == RobustLoss::None ? "none" : loopLoss == RobustLoss::Huber ? "huber" : "cauchy"), 34, 40, "robust loss on loop edges");
	c.write(s, "loop_loss_scale", loopLossScale, 34, 40, "on the whitened residual norm");
	c.write(s, "max_iterations", maxIterations, 34, 40, "Levenberg-Marquardt iterations");
	c.write(s, "function_tolerance", functionTolerance, 34, 40, "relative cost change to stop");
	c.write(s, "threads", threads, 34, 40, "Ceres threads");
}

void PoseGraph::addVertex(KeyFrameId id, const Eigen::Isometry3d& T_world_kf) { m_poses[id] = T_world_kf; }

void PoseGraph::addEdge(const PoseGraphEdge& e)
{
	if (!hasVertex(e.a) || !hasVertex(e.b))
		throw std::invalid_argument("PoseGraph::addEdge: unknown vertex " + std::to_string(hasVertex(e.a) ? e.b : e.a));
	if (e.a == e.b) throw std::invalid_argument("PoseGraph::addEdge: self edge on vertex " + std::to_string(e.a));
	if (!e.information.isApprox(e.information.transpose(), 1e-9) || e.information.llt().info() != Eigen::Success)
		throw std::invalid_argument(
			"PoseGraph::addEdge: information of edge " + std::to_string(e.a) + "->" + std::to_string(e.b) +
			" is not symmetric positive definite");
	m_edges.push_back(e);
}

void PoseGraph::setFixed(KeyFrameId id, bool fixed)
{
	if (!hasVertex(id)) throw std::invalid_argument("PoseGraph::setFixed: unknown vertex " + std::to_string(id));
	m_fixed.erase(std::remove(m_fixed.begin(), m_fixed.end(), id), m_fixed.end());
	if (fixed) m_fixed.push_back(id);
}

namespace
{
struct VertexParams
{
	double p[3];
	double q[4];  //!< x, y, z, w
};

Matrix6d sqrtInformation(const Matrix6d& info) { return info.llt().matrixU(); }

Eigen::Matrix<double, 6, 1> edgeError(const PoseGraphEdge& e, const Eigen::Isometry3d& Ta, const Eigen::Isometry3d& Tb)
{
	const Eigen::Quaterniond qa(Ta.linear()), qb(Tb.linear());
	const Eigen::Vector3d pa = Ta.translation(), pb = Tb.translation();
	double pA[3] = {pa.x(), pa.y(), pa.z()}, pB[3] = {pb.x(), pb.y(), pb.z()};
	double qA[4] = {qa.x(), qa.y(), qa.z(), qa.w()}, qB[4] = {qb.x(), qb.y(), qb.z(), qb.w()};
	RelativePoseError f(Eigen::Quaterniond(e.T_a_b.linear()), e.T_a_b.translation(), Matrix6d::Identity());
	Eigen::Matrix<double, 6, 1> r;
	f(pA, qA, pB, qB, r.data());
	return r;
}
}  // namespace

double PoseGraph::chi2() const
{
	double s = 0;
	for (const auto& e : m_edges)
	{
		const auto err = edgeError(e, m_poses.at(e.a), m_poses.at(e.b));
		s += err.dot(e.information * err);
	}
	return s;
}

PoseGraphSummary PoseGraph::optimize(const PoseGraphOptions& opts)
{
	std::string why;
	if (!opts.isValid(&why)) throw std::invalid_argument("PoseGraphOptions: " + why);
	PoseGraphSummary sum;
	std::map<KeyFrameId, VertexParams> params;
	for (const auto& [id, T] : m_poses)
	{
		VertexParams& v = params[id];
		const Eigen::Quaterniond q(T.linear());
		Eigen::Map<Eigen::Vector3d>(v.p) = T.translation();
		Eigen::Map<Eigen::Quaterniond>(v.q) = q.normalized();
	}

	ceres::Problem::Options po;
	po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
	po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
	// Owned here (declared before the problem, so they outlive it); shared by all blocks.
	ceres::EigenQuaternionManifold quaternionManifold;
	std::unique_ptr<ceres::LossFunction> loopLoss;
	if (opts.loopLoss == RobustLoss::Huber) loopLoss = std::make_unique<ceres::HuberLoss>(opts.loopLossScale);
	else if (opts.loopLoss == RobustLoss::Cauchy) loopLoss = std::make_unique<ceres::CauchyLoss>(opts.loopLossScale);
	ceres::Problem problem(po);

	for (const auto& e : m_edges)
	{
		VertexParams& a = params.at(e.a);
		VertexParams& b = params.at(e.b);
		ceres::CostFunction* cost = RelativePoseError::Create(
			Eigen::Quaterniond(e.T_a_b.linear()), e.T_a_b.translation(), sqrtInformation(e.information));
		problem.AddResidualBlock(cost, e.kind == EdgeKind::Loop ? loopLoss.get() : nullptr, a.p, a.q, b.p, b.q);
	}
	for (auto& [id, v] : params)
		if (problem.HasParameterBlock(v.q)) problem.SetManifold(v.q, &quaternionManifold);

	// Gauge freedom: every residual depends only on relative poses T_world_a^-1 T_world_b, so the
	// cost is unchanged if all vertices are moved by the same rigid transform G (T -> G T). The
	// normal equations then have a 6-dimensional null space and are singular. Holding one pose
	// constant (the first keyframe, whose pose defines the world frame) removes it.
	std::vector<KeyFrameId> fixed = m_fixed;
	if (fixed.empty() && !params.empty()) fixed.push_back(params.begin()->first);
	for (KeyFrameId id : fixed)
	{
		VertexParams& v = params.at(id);
		if (!problem.HasParameterBlock(v.p)) continue;
		problem.SetParameterBlockConstant(v.p);
		problem.SetParameterBlockConstant(v.q);
	}

	ceres::Solver::Options so;
	so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
	if (ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE))
		so.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
	else
		so.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
	so.max_num_iterations = opts.maxIterations;
	so.function_tolerance = opts.functionTolerance;
	so.num_threads = opts.threads;
	so.logging_type = ceres::SILENT;
	ceres::Solver::Summary cs;
	if (problem.NumResidualBlocks() > 0) ceres::Solve(so, &problem, &cs);
	sum.usable = problem.NumResidualBlocks() == 0 || cs.IsSolutionUsable();
	sum.initialCost = cs.initial_cost;
	sum.finalCost = cs.final_cost;
	sum.iterations = static_cast<int>(cs.iterations.size());
	sum.seconds = cs.total_time_in_seconds;
	sum.linearSolver = std::string("SPARSE_NORMAL_CHOLESKY (") +
					   ceres::SparseLinearAlgebraLibraryTypeToString(so.sparse_linear_algebra_library_type) + ")";
	sum.message = cs.message;
	if (!sum.usable) return sum;

	for (auto& [id, T] : m_poses)
	{
		const VertexParams& v = params.at(id);
		Eigen::Isometry3d Tn = Eigen::Isometry3d::Identity();
		Tn.linear() = Eigen::Quaterniond(v.q[3], v.q[0], v.q[1], v.q[2]).normalized().toRotationMatrix();
		Tn.translation() = Eigen::Vector3d(v.p[0], v.p[1], v.p[2]);
		sum.corrections.push_back(PoseCorrection{id, T, Tn});
		T = Tn;
	}
	return sum;
}

Eigen::Vector3d movePointWithKeyFrame(
	const Eigen::Vector3d& p_world, const Eigen::Isometry3d& T_world_kf_old, const Eigen::Isometry3d& T_world_kf_new)
{
	return T_world_kf_new * (T_world_kf_old.inverse() * p_world);
}

}  // namespace keygrid::loop
