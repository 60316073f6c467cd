#pragma once
/** \file PoseGraph.h
 * SE(3) keyframe pose graph: vertices T_world_kf, edges with a measured relative pose T_a_b and
 * a 6x6 information matrix (odometry/covisibility edges and loop edges), optimised with Ceres
 * (see RelativePoseError.h for the residual) using SuiteSparse sparse Cholesky.
 */
#include <keygrid/loop/BowVector.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <map>
#include <string>
#include <vector>

namespace mrpt::config
{
class CConfigFileBase;
}

namespace keygrid::loop
{
using Matrix6d = Eigen::Matrix<double, 6, 6>;

enum class EdgeKind
{
	Odometry,      //!< consecutive keyframes
	Covisibility,  //!< keyframes sharing map points
	Loop           //!< a verified loop closure (gets the robust loss)
};

struct PoseGraphEdge
{
	KeyFrameId a{0}, b{0};
	Eigen::Isometry3d T_a_b{Eigen::Isometry3d::Identity()};  //!< measured pose of b in a
	/** Information of the error (x, y, z, rx, ry, rz) [1/m^2, 1/rad^2]; symmetric positive definite */
	Matrix6d information{Matrix6d::Identity()};
	EdgeKind kind{EdgeKind::Odometry};
};

enum class RobustLoss
{
	None,
	Huber,
	Cauchy
};

struct PoseGraphOptions
{
	/** Robust loss on loop edges (Default: Huber) */
	RobustLoss loopLoss{RobustLoss::Huber};
	/** Scale of the loop-edge loss on the whitened residual norm: sqrt of the 95 % chi-square
	 * quantile for 6 DOF (Default: 3.55) */
	double loopLossScale{3.55};
	/** Levenberg-Marquardt iterations at most (Default: 100) */
	int maxIterations{100};
	/** Relative cost change at which the solver stops (Default: 1e-9) */
	double functionTolerance{1e-9};
	/** Ceres threads for Jacobian evaluation (Default: 1: deterministic and light) */
	int threads{1};

	bool isValid(std::string* why = nullptr) const;
	/** Keys loop_loss (none|huber|cauchy), loop_loss_scale, max_iterations, function_tolerance, threads. */
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section);
	void saveToConfigFile(mrpt::config::CConfigFileBase& cfg, const std::string& section) const;
};

/** What optimisation did to one keyframe (published to the maps so they re-anchor). */
struct PoseCorrection
{
	KeyFrameId id{0};
	Eigen::Isometry3d T_world_kf_old{Eigen::Isometry3d::Identity()};
	Eigen::Isometry3d T_world_kf_new{Eigen::Isometry3d::Identity()};
};

/** How the solver went (PoseGraph and Sim3PoseGraph). */
struct PoseGraphSolverReport
{
	bool usable{false};  //!< the solver returned a usable solution
	double initialCost{0}, finalCost{0};  //!< Ceres cost 0.5 sum rho(|r|^2)
	int iterations{0};
	double seconds{0};
	std::string linearSolver;  //!< e.g. "SPARSE_NORMAL_CHOLESKY (SUITE_SPARSE)"
	std::string message;
};

struct PoseGraphSummary : PoseGraphSolverReport
{
	std::vector<PoseCorrection> corrections;  //!< every vertex, old and new pose
};

class PoseGraph
{
   public:
	/** Adds or replaces a vertex. */
	void addVertex(KeyFrameId id, const Eigen::Isometry3d& T_world_kf);
	/** Both ends must exist (std::invalid_argument otherwise); the information matrix must be
	 * symmetric positive definite. */
	void addEdge(const PoseGraphEdge& e);
	/** Holds a vertex fixed. Without any, the vertex with the smallest id is fixed. */
	void setFixed(KeyFrameId id, bool fixed = true);

	bool hasVertex(KeyFrameId id) const { return m_poses.count(id) > 0; }
	const Eigen::Isometry3d& pose(KeyFrameId id) const { return m_poses.at(id); }
	const std::map<KeyFrameId, Eigen::Isometry3d>& poses() const { return m_poses; }
	const std::vector<PoseGraphEdge>& edges() const { return m_edges; }
	std::size_t numVertices() const { return m_poses.size(); }

	/** Optimises all non-fixed vertices in place; returns the summary with the corrections. */
	PoseGraphSummary optimize(const PoseGraphOptions& opts = {});

	/** Sum over edges of e^T Omega e (no robust loss): the graph's chi-square at the current poses. */
	double chi2() const;

	/** g2o text: "VERTEX_SE3:QUAT id x y z qx qy qz qw" then
	 * "EDGE_SE3:QUAT a b x y z qx qy qz qw" + the 21 upper-triangular information entries
	 * (row-major). Loop edges are preceded by a "# loop" comment line; fixed vertices by "FIX id". */
	void writeG2o(const std::string& path) const;
	/** Reads what writeG2o writes (and plain g2o SE3 graphs); throws naming the line on errors. */
	static PoseGraph readG2o(const std::string& path);

   private:
	std::map<KeyFrameId, Eigen::Isometry3d> m_poses;
	std::vector<PoseGraphEdge> m_edges;
	std::vector<KeyFrameId> m_fixed;
};

/** A map point follows its reference keyframe: given p_world computed with T_world_kf_old,
 * returns T_world_kf_new * T_world_kf_old^-1 * p_world (the point keeps its position in the
 * keyframe's frame). */
Eigen::Vector3d movePointWithKeyFrame(
	const Eigen::Vector3d& p_world, const Eigen::Isometry3d& T_world_kf_old, const Eigen::Isometry3d& T_world_kf_new);

}  // namespace keygrid::loop
