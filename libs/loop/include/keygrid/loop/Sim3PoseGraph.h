#pragma once
/** \file Sim3PoseGraph.h
 * Sim(3) keyframe pose graph for monocular maps, whose scale is arbitrary and drifts: vertices
 * S_world_kf (rotation, translation and scale: 7 DOF), edges with a measured relative similarity
 * S_a_b and a 7x7 information matrix, optimised with Ceres (see RelativeSim3Error.h for the
 * residual) using SuiteSparse sparse Cholesky. The monocular counterpart of PoseGraph and of
 * ORB-SLAM's essential-graph optimisation: odometry and covisibility edges keep the keyframes'
 * current relative poses at unit relative scale, the loop edge carries the similarity found by
 * loop detection, and the scale correction it brings is spread over the keyframes of the loop.
 */
#include <keygrid/loop/PoseGraph.h>
#include <keygrid/loop/Sim3.h>

#include <Eigen/Core>
#include <map>
#include <vector>

namespace keygrid::loop
{
using Matrix7d = Eigen::Matrix<double, 7, 7>;

struct Sim3PoseGraphEdge
{
	KeyFrameId a{0}, b{0};
	Sim3 S_a_b;  //!< measured similarity of b in a (b's coordinates -> a's)
	/** Information of the error (x, y, z, rx, ry, rz, log s) [1/(units of b)^2, 1/rad^2, 1];
	 * symmetric positive definite */
	Matrix7d information{Matrix7d::Identity()};
	EdgeKind kind{EdgeKind::Odometry};
};

/** What optimisation did to one keyframe. */
struct Sim3Correction
{
	KeyFrameId id{0};
	Sim3 S_world_kf_old;
	Sim3 S_world_kf_new;
};

struct Sim3PoseGraphSummary : PoseGraphSolverReport
{
	std::vector<Sim3Correction> corrections;  //!< every vertex, old and new similarity
};

class Sim3PoseGraph
{
   public:
	/** Adds or replaces a vertex. Throws std::invalid_argument for a scale that is not positive
	 * and finite or a zero quaternion; the quaternion is normalised. */
	void addVertex(KeyFrameId id, const Sim3& S_world_kf);
	/** Both ends must exist and differ, S_a_b must be valid as for addVertex, the information
	 * symmetric positive definite (std::invalid_argument otherwise). */
	void addEdge(const Sim3PoseGraphEdge& e);
	/** Holds a vertex fixed (rotation, translation and scale). Without any, the vertex with the
	 * smallest id is fixed. */
	void setFixed(KeyFrameId id, bool fixed = true);
	/** Holds every vertex's scale at its value: the map's units are known everywhere (a
	 * monocular map made metric), so a loop moves and turns keyframes but does not rescale
	 * them, as ORB-SLAM's essential graph with a fixed scale (Default: false) */
	void setScalesFixed(bool fixed) { m_scalesFixed = fixed; }

	bool hasVertex(KeyFrameId id) const { return m_poses.count(id) > 0; }
	const Sim3& pose(KeyFrameId id) const { return m_poses.at(id); }
	const std::map<KeyFrameId, Sim3>& poses() const { return m_poses; }
	const std::vector<Sim3PoseGraphEdge>& edges() const { return m_edges; }
	std::size_t numVertices() const { return m_poses.size(); }

	/** PoseGraphOptions with the loop-edge loss scaled for 7 DOF: loopLossScale = 3.75, sqrt of
	 * the 95 % chi-square quantile for 7 DOF. */
	static PoseGraphOptions defaultOptions();

	/** Optimises all non-fixed vertices in place; returns the summary with the corrections. */
	Sim3PoseGraphSummary optimize(const PoseGraphOptions& opts = defaultOptions());

	/** Sum over edges of e^T Omega e (no robust loss): the graph's chi-square at the current poses. */
	double chi2() const;

   private:
	std::map<KeyFrameId, Sim3> m_poses;
	std::vector<Sim3PoseGraphEdge> m_edges;
	std::vector<KeyFrameId> m_fixed;
	bool m_scalesFixed{false};
};

/** The SE(3) form of a Sim(3) correction, for maps that keep rigid keyframe poses (ORB-SLAM's
 * T_cw = [R | t / s] after the essential graph). The keyframe's pose becomes the rotation and
 * translation of S_world_kf_new (camera centre and orientation do not depend on the scale), and
 * its points' camera coordinates are multiplied by pointScale = s_new / s_old, so that
 *     T_world_kf_new (pointScale T_world_kf_old^-1 p_world) = S_world_kf_new S_world_kf_old^-1 p_world.
 */
struct RigidCorrection
{
	PoseCorrection pose;  //!< the rigid parts of S_world_kf_old and S_world_kf_new
	double pointScale{1};  //!< s_new / s_old
};

RigidCorrection toRigidCorrection(const Sim3Correction& c);

/** A map point follows its reference keyframe: S_world_kf_new S_world_kf_old^-1 p_world (the
 * point keeps its position in the keyframe's frame, in the keyframe's units). */
Eigen::Vector3d movePointWithKeyFrame(
	const Eigen::Vector3d& p_world, const Sim3& S_world_kf_old, const Sim3& S_world_kf_new);

}  // namespace keygrid::loop
