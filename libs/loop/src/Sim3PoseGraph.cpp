#include "PoseGraphSolver.h"

#include <keygrid/loop/RelativeSim3Error.h>
#include <keygrid/loop/Sim3PoseGraph.h>

#include <cmath>
#include <stdexcept>

namespace keygrid::loop
{
namespace
{
/** Throws std::invalid_argument naming what (e.g. "Sim3PoseGraph::addVertex: vertex 3") for a
 * scale that is not positive and finite, a zero or non-finite rotation or a non-finite
 * translation; returns the similarity with a unit quaternion. */
Sim3 checkedSim3(const Sim3& S, const std::string& what)
{
	if (!(S.s > 0) || !std::isfinite(S.s))
		throw std::invalid_argument(what + ": scale " + std::to_string(S.s) + " (must be positive and finite)");
	if (!S.q.coeffs().allFinite() || !(S.q.norm() > 1e-12))
		throw std::invalid_argument(what + ": rotation quaternion is zero or not finite");
	if (!S.t.allFinite()) throw std::invalid_argument(what + ": translation is not finite");
	return Sim3{S.q.normalized(), S.t, S.s};
}

Eigen::Matrix<double, 7, 1> edgeError(const Sim3PoseGraphEdge& e, const Sim3& Sa, const Sim3& Sb)
{
	const detail::VertexBlocks a(Sa.t, Sa.q, std::log(Sa.s)), b(Sb.t, Sb.q, std::log(Sb.s));
	const RelativeSim3Error f(e.S_a_b, Matrix7d::Identity());
	Eigen::Matrix<double, 7, 1> r;
	f(a.t, a.q, &a.logScale, b.t, b.q, &b.logScale, r.data());
	return r;
}
}  // namespace

void Sim3PoseGraph::addVertex(KeyFrameId id, const Sim3& S_world_kf)
{
	m_poses[id] = checkedSim3(S_world_kf, "Sim3PoseGraph::addVertex: vertex " + std::to_string(id));
}

void Sim3PoseGraph::addEdge(const Sim3PoseGraphEdge& e)
{
	detail::checkEdge("Sim3PoseGraph", *this, e);
	Sim3PoseGraphEdge checked = e;
	checked.S_a_b =
		checkedSim3(e.S_a_b, "Sim3PoseGraph::addEdge: edge " + std::to_string(e.a) + "->" + std::to_string(e.b));
	m_edges.push_back(checked);
}

void Sim3PoseGraph::setFixed(KeyFrameId id, bool fixed)
{
	detail::setFixedVertex("Sim3PoseGraph", *this, m_fixed, id, fixed);
}

PoseGraphOptions Sim3PoseGraph::defaultOptions()
{
	PoseGraphOptions o;
	o.loopLossScale = 3.75;
	return o;
}

double Sim3PoseGraph::chi2() const
{
	return detail::chiSquare(m_edges, [&](const Sim3PoseGraphEdge& e) { return edgeError(e, m_poses.at(e.a), m_poses.at(e.b)); });
}

Sim3PoseGraphSummary Sim3PoseGraph::optimize(const PoseGraphOptions& opts)
{
	detail::GraphProblem problem(opts);
	for (const auto& [id, S] : m_poses) problem.addVertex(id, detail::VertexBlocks(S.t, S.q, std::log(S.s)));
	for (const auto& e : m_edges)
	{
		detail::VertexBlocks& a = problem.vertex(e.a);
		detail::VertexBlocks& b = problem.vertex(e.b);
		ceres::CostFunction* cost = RelativeSim3Error::Create(e.S_a_b, detail::sqrtInformation(e.information));
		problem.addResidual(cost, e.kind, {a.t, a.q, &a.logScale, b.t, b.q, &b.logScale});
	}
	if (m_scalesFixed) problem.holdScalesConstant();

	// Gauge freedom: every residual depends only on relative similarities S_world_a^-1 S_world_b,
	// so the cost is unchanged if all vertices are moved by the same similarity G (S -> G S):
	// a 7-dimensional null space (rotation, translation and the map's overall scale). Holding one
	// vertex constant, scale included (the first keyframe, or the loop's matched keyframe set
	// with setFixed), removes it and ties the corrected map's units to that keyframe's.
	Sim3PoseGraphSummary sum{problem.solve(detail::gaugeVertices(m_fixed, m_poses)), {}};
	if (!sum.usable) return sum;

	for (auto& [id, S] : m_poses)
	{
		const detail::VertexBlocks& v = problem.vertex(id);
		const Sim3 Sn{v.rotation(), v.translation(), std::exp(v.logScale)};
		sum.corrections.push_back(Sim3Correction{id, S, Sn});
		S = Sn;
	}
	return sum;
}

RigidCorrection toRigidCorrection(const Sim3Correction& c)
{
	return RigidCorrection{
		PoseCorrection{c.id, c.S_world_kf_old.rigid(), c.S_world_kf_new.rigid()}, c.S_world_kf_new.s / c.S_world_kf_old.s};
}

Eigen::Vector3d movePointWithKeyFrame(
	const Eigen::Vector3d& p_world, const Sim3& S_world_kf_old, const Sim3& S_world_kf_new)
{
	return S_world_kf_new * (S_world_kf_old.inverse() * p_world);
}

}  // namespace keygrid::loop
