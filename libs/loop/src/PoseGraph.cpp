#include "PoseGraphSolver.h"

#include <keygrid/loop/PoseGraph.h>
#include <keygrid/loop/RelativePoseError.h>
#include <mrpt/config/CConfigFileBase.h>

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
	detail::checkEdge("PoseGraph", *this, e);
	m_edges.push_back(e);
}

void PoseGraph::setFixed(KeyFrameId id, bool fixed) { detail::setFixedVertex("PoseGraph", *this, m_fixed, id, fixed); }

namespace
{
Eigen::Matrix<double, 6, 1> edgeError(const PoseGraphEdge& e, const Eigen::Isometry3d& Ta, const Eigen::Isometry3d& Tb)
{
	const detail::VertexBlocks a(Ta.translation(), Eigen::Quaterniond(Ta.linear()));
	const detail::VertexBlocks b(Tb.translation(), Eigen::Quaterniond(Tb.linear()));
	const RelativePoseError f(Eigen::Quaterniond(e.T_a_b.linear()), e.T_a_b.translation(), Matrix6d::Identity());
	Eigen::Matrix<double, 6, 1> r;
	f(a.t, a.q, b.t, b.q, r.data());
	return r;
}
}  // namespace

double PoseGraph::chi2() const
{
	return detail::chiSquare(m_edges, [&](const PoseGraphEdge& e) { return edgeError(e, m_poses.at(e.a), m_poses.at(e.b)); });
}

PoseGraphSummary PoseGraph::optimize(const PoseGraphOptions& opts)
{
	detail::GraphProblem problem(opts);
	for (const auto& [id, T] : m_poses) problem.addVertex(id, detail::VertexBlocks(T.translation(), Eigen::Quaterniond(T.linear())));
	for (const auto& e : m_edges)
	{
		detail::VertexBlocks& a = problem.vertex(e.a);
		detail::VertexBlocks& b = problem.vertex(e.b);
		ceres::CostFunction* cost = RelativePoseError::Create(
			Eigen::Quaterniond(e.T_a_b.linear()), e.T_a_b.translation(), detail::sqrtInformation(e.information));
		problem.addResidual(cost, e.kind, {a.t, a.q, b.t, b.q});
	}

	// Gauge freedom: every residual depends only on relative poses T_world_a^-1 T_world_b, so the
	// cost is unchanged if all vertices are moved by the same rigid transform G (T -> G T). The
	// normal equations then have a 6-dimensional null space and are singular. Holding one pose
	// constant (the first keyframe, whose pose defines the world frame) removes it.
	PoseGraphSummary sum{problem.solve(detail::gaugeVertices(m_fixed, m_poses)), {}};
	if (!sum.usable) return sum;

	for (auto& [id, T] : m_poses)
	{
		const detail::VertexBlocks& v = problem.vertex(id);
		Eigen::Isometry3d Tn = Eigen::Isometry3d::Identity();
		Tn.linear() = v.rotation().toRotationMatrix();
		Tn.translation() = v.translation();
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
