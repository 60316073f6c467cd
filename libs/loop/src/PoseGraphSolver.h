#pragma once
/** \file PoseGraphSolver.h (private)
 * What the SE(3) and Sim(3) pose graphs share: edge checks, the gauge choice, chi-square, and
 * the Ceres problem (parameter blocks, loop-edge loss, quaternion manifold, sparse solve).
 */
#include <ceres/loss_function.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <keygrid/loop/PoseGraph.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace keygrid::loop::detail
{
/** Throws std::invalid_argument (prefixed with graph, e.g. "PoseGraph") unless the edge joins
 * two distinct vertices of the graph and its information is symmetric positive definite. */
template <class Graph, class Edge>
void checkEdge(const std::string& graph, const Graph& g, const Edge& e)
{
	if (!g.hasVertex(e.a) || !g.hasVertex(e.b))
		throw std::invalid_argument(graph + "::addEdge: unknown vertex " + std::to_string(g.hasVertex(e.a) ? e.b : e.a));
	if (e.a == e.b) throw std::invalid_argument(graph + "::addEdge: self edge on vertex " + std::to_string(e.a));
	if (!e.information.isApprox(e.information.transpose(), 1e-9) || e.information.llt().info() != Eigen::Success)
		throw std::invalid_argument(
			graph + "::addEdge: information of edge " + std::to_string(e.a) + "->" + std::to_string(e.b) +
			" is not symmetric positive definite");
}

/** U with Omega = U^T U (upper-triangular Cholesky factor): |U e|^2 = e^T Omega e. */
template <int N>
Eigen::Matrix<double, N, N> sqrtInformation(const Eigen::Matrix<double, N, N>& info)
{
	return info.llt().matrixU();
}

/** Adds or removes id in the fixed list; throws std::invalid_argument for an unknown vertex. */
template <class Graph>
void setFixedVertex(const std::string& graph, const Graph& g, std::vector<KeyFrameId>& fixedIds, KeyFrameId id, bool fixed)
{
	if (!g.hasVertex(id)) throw std::invalid_argument(graph + "::setFixed: unknown vertex " + std::to_string(id));
	fixedIds.erase(std::remove(fixedIds.begin(), fixedIds.end(), id), fixedIds.end());
	if (fixed) fixedIds.push_back(id);
}

/** The vertices to hold constant: those set fixed, or else the smallest id (the oldest keyframe,
 * whose pose defines the world frame). */
template <class Vertex>
std::vector<KeyFrameId> gaugeVertices(const std::vector<KeyFrameId>& fixedIds, const std::map<KeyFrameId, Vertex>& vertices)
{
	if (!fixedIds.empty() || vertices.empty()) return fixedIds;
	return {vertices.begin()->first};
}

/** Sum over edges of e^T Omega e, with error(edge) the unwhitened error e of the edge. */
template <class Edge, class ErrorFn>
double chiSquare(const std::vector<Edge>& edges, ErrorFn error)
{
	double s = 0;
	for (const auto& e : edges)
	{
		const auto err = error(e);
		s += err.dot(e.information * err);
	}
	return s;
}

/** One vertex's Ceres parameter blocks. */
struct VertexBlocks
{
	double t[3];
	double q[4];  //!< unit quaternion, Eigen's order x, y, z, w
	double logScale{0};  //!< Sim(3) only

	VertexBlocks(const Eigen::Vector3d& translation, const Eigen::Quaterniond& rotation, double logS = 0);
	Eigen::Vector3d translation() const { return Eigen::Vector3d(t[0], t[1], t[2]); }
	/** Normalised. */
	Eigen::Quaterniond rotation() const { return Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized(); }
};

/** The Ceres problem of a keyframe graph: parameter blocks per vertex, edge residuals (loop edges
 * with the options' robust loss), the quaternion manifold, fixed vertices, sparse solve. */
class GraphProblem
{
   public:
	/** Throws std::invalid_argument ("PoseGraphOptions: ...") for invalid options. */
	explicit GraphProblem(const PoseGraphOptions& opts);

	void addVertex(KeyFrameId id, const VertexBlocks& v) { m_vertices.emplace(id, v); }
	VertexBlocks& vertex(KeyFrameId id) { return m_vertices.at(id); }
	/** The residual of an edge of the given kind over blocks of its two vertices. */
	void addResidual(ceres::CostFunction* cost, EdgeKind kind, const std::vector<double*>& blocks);
	/** Holds every vertex's scale block constant (Sim(3) graphs of a metric map). */
	void holdScalesConstant();

	/** Holds every block of the fixed vertices constant and solves with SPARSE_NORMAL_CHOLESKY
	 * (SuiteSparse, Eigen's sparse Cholesky if Ceres lacks it) within the options' limits. A
	 * problem without residuals is already optimal. */
	PoseGraphSolverReport solve(const std::vector<KeyFrameId>& fixed);

   private:
	PoseGraphOptions m_opts;
	// Declared before the problem, so they outlive it; shared by all blocks.
	ceres::EigenQuaternionManifold m_quaternionManifold;
	std::unique_ptr<ceres::LossFunction> m_loopLoss;
	std::map<KeyFrameId, VertexBlocks> m_vertices;  //!< node-based: block addresses stay valid
	ceres::Problem m_problem;
};

}  // namespace keygrid::loop::detail
