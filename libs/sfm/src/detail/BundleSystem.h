#pragma once
/** \file BundleSystem.h
 * The pieces of the dedicated bundle solver (BundleLevenbergMarquardt.h): the problem's index
 * structure, its linearisation (the blocks U, V, W and the gradient) and the reduced camera
 * system (Schur complement of the points, CHOLMOD supernodal Cholesky).
 */
#include <keygrid/sfm/BundleLevenbergMarquardt.h>

#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>
#include <array>
#include <cstddef>
#include <future>
#include <vector>

namespace keygrid::sfm::detail
{
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Matrix63 = Eigen::Matrix<double, 6, 3>;

/** Points are worked on in this many fixed, contiguous parts, one thread each. */
constexpr int kBundlePartitions = 2;

/** Runs f(part) for every part, part 0 on the calling thread; rethrows a part's exception. */
template <class F>
void forEachPartition(const F& f)
{
	static_assert(kBundlePartitions == 2, "one helper thread");
	auto other = std::async(std::launch::async, [&] { f(1); });
	f(0);
	other.get();
}

/** Indices of a bundle problem: moving cameras, each point's terms, the point partitions. */
struct BundleIndex
{
	/** Per camera: its index among the moving cameras (rows of the reduced system), or -1. */
	std::vector<int> var;
	int moving{0};
	/** Terms of point j: [pointBegin[j], pointBegin[j + 1]). */
	std::vector<std::size_t> pointBegin;
	/** Points of part p: [partBegin[p], partBegin[p + 1]), split at half the terms. */
	std::array<std::size_t, kBundlePartitions + 1> partBegin{};

	/** Throws std::invalid_argument for indices out of range or terms not sorted by point. */
	BundleIndex(const std::vector<BundleCamera>& cameras, std::size_t points, const std::vector<BundleTerm>& terms);
	std::size_t points() const { return pointBegin.size() - 1; }
};

/** The Gauss-Newton blocks at the current parameters (Huber re-weighted). */
struct BundleLinearization
{
	double cost{0};
	std::vector<Matrix6d> U;      //!< per moving camera
	Eigen::VectorXd gc;           //!< camera gradient, 6 per moving camera
	std::vector<Eigen::Matrix3d> V;  //!< per point
	std::vector<Eigen::Vector3d> gp;  //!< point gradient
	std::vector<Matrix63> W;      //!< per term (zero for a fixed camera)

	/** Evaluates everything at (cameras, points); false when a point is behind its camera. */
	bool evaluate(
		const BundleIndex& index, const std::vector<BundleCamera>& cameras, const std::vector<Eigen::Vector3d>& points,
		const std::vector<BundleTerm>& terms, const PinholeIntrinsics& K, double bf);
	/** Max norm of the gradient. */
	double gradientMaxNorm() const;
	/** g . step + 1/2 step^T H step (H undamped), the model's cost change for a step. */
	double modelChange(const BundleIndex& index, const std::vector<BundleTerm>& terms, const Eigen::VectorXd& dc,
		const std::vector<Eigen::Vector3d>& dp) const;
};

/** The reduced camera system: its block pattern and symbolic factorisation are computed once. */
class ReducedCameraSystem
{
   public:
	ReducedCameraSystem(const BundleIndex& index, const std::vector<BundleTerm>& terms);

	/** The damped step for `lin`, `damping(d)` giving the damping of a diagonal entry d.
	 * False when the factorisation fails. */
	template <class Damping>
	bool solve(const BundleLinearization& lin, const Damping& damping, Eigen::VectorXd& dc, std::vector<Eigen::Vector3d>& dp);

   private:
	/** Per part: the point eliminations summed into its own block copies and right-hand side. */
	struct PartSums
	{
		std::vector<Matrix6d> blocks;
		Eigen::VectorXd rhs;
	};
	void eliminatePoints(const BundleLinearization& lin, int part, PartSums& sums);
	bool factorAndSolve(const BundleLinearization& lin, const std::vector<double>& cameraDamping, Eigen::VectorXd& dc);
	void backSubstitute(const BundleLinearization& lin, const Eigen::VectorXd& dc, std::vector<Eigen::Vector3d>& dp) const;

	const BundleIndex& m_index;
	const std::vector<BundleTerm>& m_terms;
	/** (row camera, column camera), row >= column: the lower-triangular 6x6 blocks. */
	std::vector<std::pair<int, int>> m_blocks;
	/** Per point: the blocks of its pairs of moving terms (a >= b, in term order). */
	std::vector<std::size_t> m_pairBegin;
	std::vector<int> m_pairBlock;
	/** Lower triangle of the reduced matrix; entry (r, c) of block k at valuePtr()[m_valueIndex[36 k + 6 r + c]]
	 * (-1: above the diagonal of a diagonal block). */
	Eigen::SparseMatrix<double> m_S;
	std::vector<int> m_valueIndex;
	Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> m_cholesky;
	/** (V_j + D_pj)^-1 of the last solve, for the back-substitution. */
	std::vector<Eigen::Matrix3d> m_Vinv;
	std::vector<double> m_pointDamping;
	PartSums m_parts[kBundlePartitions];
};

template <class Damping>
bool ReducedCameraSystem::solve(
	const BundleLinearization& lin, const Damping& damping, Eigen::VectorXd& dc, std::vector<Eigen::Vector3d>& dp)
{
	m_pointDamping.resize(3 * m_index.points());
	for (std::size_t j = 0; j < m_index.points(); j++)
		for (int k = 0; k < 3; k++) m_pointDamping[3 * j + k] = damping(lin.V[j](k, k));
	std::vector<double> cameraDamping(6 * static_cast<std::size_t>(m_index.moving));
	for (int i = 0; i < m_index.moving; i++)
		for (int k = 0; k < 6; k++) cameraDamping[6 * static_cast<std::size_t>(i) + k] = damping(lin.U[i](k, k));
	forEachPartition([&](int part) { eliminatePoints(lin, part, m_parts[part]); });
	if (!factorAndSolve(lin, cameraDamping, dc)) return false;
	backSubstitute(lin, dc, dp);
	return true;
}

}  // namespace keygrid::sfm::detail
