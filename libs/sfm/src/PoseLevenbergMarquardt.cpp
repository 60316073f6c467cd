#include <keygrid/sfm/PoseLevenbergMarquardt.h>

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

constexpr double kMinDepth = 1e-6;
constexpr double kMinLmDiagonal = 1e-6, kMaxLmDiagonal = 1e32;
constexpr double kMinRelativeDecrease = 1e-3;
constexpr double kMaxRadius = 1e16, kMinRadius = 1e-32;

/** rho(s) and rho'(s) of the Huber loss with threshold delta (delta = 0: rho(s) = s). */
void huber(double s, double delta, double& rho, double& rho1)
{
	if (delta <= 0 || s <= delta * delta)
	{
		rho = s;
		rho1 = 1.0;
		return;
	}
	const double r = std::sqrt(s);
	rho = 2.0 * delta * r - delta * delta;
	rho1 = delta / r;
}

/** Residual r of `term` at p_cam; false behind the camera. */
bool residualAt(const Eigen::Vector3d& pc, const PoseResidualTerm& term, const PinholeIntrinsics& K, double bf, Eigen::Vector3d& r)
{
	if (pc.z() <= kMinDepth) return false;
	const double iz = 1.0 / pc.z();
	r.x() = (term.uv.x() - (K.fx * pc.x() * iz + K.cx)) * term.invSigma;
	r.y() = (term.uv.y() - (K.fy * pc.y() * iz + K.cy)) * term.invSigma;
	r.z() = term.disparity > 0 ? (term.disparity - bf * iz) * term.invSigmaDisparity : 0.0;
	return true;
}

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
		// d r / d p_cam (third row zero without depth)
		const double iz = 1.0 / pc.z(), e = -term.invSigma;
		Eigen::Matrix3d Jpc;
		Jpc << e * K.fx * iz, 0.0, -e * K.fx * pc.x() * iz * iz,  //
			0.0, e * K.fy * iz, -e * K.fy * pc.y() * iz * iz,  //
			0.0, 0.0, term.disparity > 0 ? term.invSigmaDisparity * bf * iz * iz : 0.0;
		// d p_cam / d w = -[R p]x, d p_cam / d dt = I
		Eigen::Matrix<double, 3, 6> J;
		Eigen::Matrix3d skewRp;
		skewRp << 0, -Rp.z(), Rp.y(), Rp.z(), 0, -Rp.x(), -Rp.y(), Rp.x(), 0;
		J.leftCols<3>() = -Jpc * skewRp;
		J.rightCols<3>() = Jpc;
		g.noalias() += rho1 * (J.transpose() * r);
		H.noalias() += rho1 * (J.transpose() * J);
	}
	return true;
}

Eigen::Matrix3d expSO3(const Eigen::Vector3d& w)
{
	const double angle = w.norm();
	if (angle < 1e-12)
	{
		Eigen::Matrix3d S;
		S << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
		return Eigen::Matrix3d::Identity() + S;
	}
	return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
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
	double radius = o.initialTrustRegionRadius, decreaseFactor = 2.0;
	const auto xNorm = [&] { return std::sqrt(1.0 + t.squaredNorm()); };  // |(unit quaternion, t)|
	while (s.iterations < o.maxIterations && g.lpNorm<Eigen::Infinity>() > o.gradientTolerance)
	{
		s.iterations++;
		Matrix6d A = H;
		for (int k = 0; k < 6; k++) A(k, k) += std::clamp(H(k, k), kMinLmDiagonal, kMaxLmDiagonal) / radius;
		const Vector6d step = A.ldlt().solve(-g);
		if (!step.allFinite()) break;
		if (step.norm() <= o.parameterTolerance * (xNorm() + o.parameterTolerance)) break;
		const Eigen::Matrix3d Rc = expSO3(step.head<3>()) * R;
		const Eigen::Vector3d tc = t + step.tail<3>();
		const double candidate = costAt(Rc, tc, terms, K, bf);
		// Stop when the cost no longer changes (the last step is not taken, as in Ceres).
		if (std::abs(cost - candidate) <= o.functionTolerance * cost) break;
		const double modelDecrease = -(g.dot(step) + 0.5 * step.dot(H * step));
		const double rho = (cost - candidate) / modelDecrease;
		if (std::isfinite(candidate) && modelDecrease > 0 && rho > kMinRelativeDecrease)
		{
			R = Rc;
			t = tc;
			s.successfulIterations++;
			radius = std::min(kMaxRadius, radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3)));
			decreaseFactor = 2.0;
			linearize(R, t, terms, K, bf, cost, g, H);
			s.finalCost = cost;
		}
		else
		{
			radius /= decreaseFactor;
			decreaseFactor *= 2.0;
			if (radius < kMinRadius) break;
		}
	}
	return s;
}

}  // namespace keygrid::sfm
