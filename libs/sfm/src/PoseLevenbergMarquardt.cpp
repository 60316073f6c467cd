#include <keygrid/sfm/PoseLevenbergMarquardt.h>

#include "detail/RobustReprojection.h"
#include "detail/TrustRegion.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace keygrid::sfm
{
namespace
{
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

using detail::huber;
using detail::residualAt;

/** Robust cost 1/2 sum rho(|r|^2); +inf when a point is behind the camera. */
double costAt(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const std::vector<PoseResidualTerm>& terms, const PinholeIntrinsics& K, double bf)
{
	double cost = 0;
	for (const auto& term : terms)
	{
		Eigen::Vector3d r;
		if (!residualAt(R * term.p_world + t, term, K, bf, r)) return std::numeric_limits<double>::infinity();
		double rho, rho1;
		huber(r.squaredNorm(), term.huberDelta, rho, rho1);
		cost += 0.5 * rho;
	}
	return cost;
}

/** Robust cost, gradient J^T W r and Gauss-Newton matrix J^T W J at (R, t); false behind. */
bool linearize(
	const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const std::vector<PoseResidualTerm>& terms, const PinholeIntrinsics& K,
	double bf, double& cost, Vector6d& g, Matrix6d& H)
{
	cost = 0;
	g.setZero();
	H.setZero();
	for (const auto& term : terms)
	{
		const Eigen::Vector3d Rp = R * term.p_world;
		const Eigen::Vector3d pc = Rp + t;
		Eigen::Vector3d r;
		if (!residualAt(pc, term, K, bf, r)) return false;
		double rho, rho1;
		huber(r.squaredNorm(), term.huberDelta, rho, rho1);
		cost += 0.5 * rho;
		const Eigen::Matrix3d Jpc = detail::residualJacobian(pc, term, K, bf);
		// d p_cam / d w = -[R p]x, d p_cam / d dt = I
		Eigen::Matrix<double, 3, 6> J;
		J.leftCols<3>() = -Jpc * detail::skew(Rp);
		J.rightCols<3>() = Jpc;
		g.noalias() += rho1 * (J.transpose() * r);
		H.noalias() += rho1 * (J.transpose() * J);
	}
	return true;
}

}  // namespace

bool poseResidualSquaredNorm(
	const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const PoseResidualTerm& term, const PinholeIntrinsics& K, double bf,
	double& squaredNorm)
{
	Eigen::Vector3d r;
	if (!residualAt(R * term.p_world + t, term, K, bf, r)) return false;
	squaredNorm = r.squaredNorm();
	return true;
}

PoseSolverSummary solvePoseLevenbergMarquardt(
	Eigen::Matrix3d& R, Eigen::Vector3d& t, const std::vector<PoseResidualTerm>& terms, const PinholeIntrinsics& K, double bf,
	const PoseSolverOptions& o)
{
	PoseSolverSummary s;
	double cost;
	Vector6d g;
	Matrix6d H;
	if (!linearize(R, t, terms, K, bf, cost, g, H))
	{
		s.usable = false;
		s.initialCost = s.finalCost = std::numeric_limits<double>::infinity();
		return s;
	}
	s.initialCost = s.finalCost = cost;
	detail::TrustRegion region(o.initialTrustRegionRadius);
	const auto xNorm = [&] { return std::sqrt(1.0 + t.squaredNorm()); };  // |(unit quaternion, t)|
	while (s.iterations < o.maxIterations && g.lpNorm<Eigen::Infinity>() > o.gradientTolerance)
	{
		s.iterations++;
		Matrix6d A = H;
		for (int k = 0; k < 6; k++) A(k, k) += region.damping(H(k, k));
		const Vector6d step = A.ldlt().solve(-g);
		if (!step.allFinite()) break;
		if (step.norm() <= o.parameterTolerance * (xNorm() + o.parameterTolerance)) break;
		const Eigen::Matrix3d Rc = detail::expSO3(step.head<3>()) * R;
		const Eigen::Vector3d tc = t + step.tail<3>();
		const double candidate = costAt(Rc, tc, terms, K, bf);
		// Stop when the cost no longer changes (the last step is not taken, as in Ceres).
		if (std::abs(cost - candidate) <= o.functionTolerance * cost) break;
		const double modelDecrease = -(g.dot(step) + 0.5 * step.dot(H * step));
		if (detail::TrustRegion::accepts(cost - candidate, modelDecrease))
		{
			R = Rc;
			t = tc;
			s.successfulIterations++;
			region.grow((cost - candidate) / modelDecrease);
			linearize(R, t, terms, K, bf, cost, g, H);
			s.finalCost = cost;
		}
		else if (!region.shrink())
			break;
	}
	return s;
}

}  // namespace keygrid::sfm
