/** \file BundleLevenbergMarquardt.cpp
 * The Levenberg-Marquardt loop of the dedicated bundle solver; the linear algebra is in
 * BundleSystem.cpp.
 */
#include <keygrid/sfm/BundleLevenbergMarquardt.h>

#include "detail/BundleSystem.h"
#include "detail/RobustReprojection.h"
#include "detail/TrustRegion.h"

#include <chrono>
#include <cmath>
#include <limits>

namespace keygrid::sfm
{
namespace
{
double secondsSince(std::chrono::steady_clock::time_point t0)
{
	return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/** The parameters after a step (moving cameras and every point). */
struct Candidate
{
	std::vector<BundleCamera> cameras;
	std::vector<Eigen::Vector3d> points;
};

Candidate stepped(
	const detail::BundleIndex& index, const std::vector<BundleCamera>& cameras, const std::vector<Eigen::Vector3d>& points,
	const Eigen::VectorXd& dc, const std::vector<Eigen::Vector3d>& dp)
{
	Candidate c{cameras, points};
	for (std::size_t i = 0; i < cameras.size(); i++)
		if (const int v = index.var[i]; v >= 0)
		{
			c.cameras[i].R_cam_world = detail::expSO3(dc.segment<3>(6 * v)) * cameras[i].R_cam_world;
			c.cameras[i].t_cam_world += dc.segment<3>(6 * v + 3);
		}
	for (std::size_t j = 0; j < points.size(); j++) c.points[j] += dp[j];
	return c;
}

/** Robust cost 1/2 sum rho(|r|^2); +inf when a point is behind its camera. */
double costAt(
	const detail::BundleIndex& index, const Candidate& x, const std::vector<BundleTerm>& terms, const PinholeIntrinsics& K,
	double bf)
{
	double parts[detail::kBundlePartitions] = {0, 0};
	detail::forEachPartition(
		[&](int p)
		{
			double sum = 0;
			for (std::size_t k = index.pointBegin[index.partBegin[p]]; k < index.pointBegin[index.partBegin[p + 1]]; k++)
			{
				const auto& term = terms[k];
				const auto& cam = x.cameras[static_cast<std::size_t>(term.camera)];
				Eigen::Vector3d r;
				if (!detail::residualAt(cam.R_cam_world * x.points[static_cast<std::size_t>(term.point)] + cam.t_cam_world, term, K, bf, r))
				{
					sum = std::numeric_limits<double>::infinity();
					break;
				}
				double rho, rho1;
				detail::huber(r.squaredNorm(), term.huberDelta, rho, rho1);
				sum += 0.5 * rho;
			}
			parts[p] = sum;
		});
	return parts[0] + parts[1];
}

/** |x| over the variables: unit quaternions of the moving cameras, their translations, the points. */
double parameterNorm(const detail::BundleIndex& index, const std::vector<BundleCamera>& cameras, const std::vector<Eigen::Vector3d>& points)
{
	double s = 0;
	for (std::size_t i = 0; i < cameras.size(); i++)
		if (index.var[i] >= 0) s += 1.0 + cameras[i].t_cam_world.squaredNorm();
	for (const auto& p : points) s += p.squaredNorm();
	return std::sqrt(s);
}

double stepNorm(const Eigen::VectorXd& dc, const std::vector<Eigen::Vector3d>& dp)
{
	double s = dc.squaredNorm();
	for (const auto& d : dp) s += d.squaredNorm();
	return std::sqrt(s);
}
}  // namespace

bool bundleResidualSquaredNorm(
	const BundleCamera& camera, const Eigen::Vector3d& point, const BundleTerm& term, const PinholeIntrinsics& K, double bf,
	double& squaredNorm)
{
	Eigen::Vector3d r;
	if (!detail::residualAt(camera.R_cam_world * point + camera.t_cam_world, term, K, bf, r)) return false;
	squaredNorm = r.squaredNorm();
	return true;
}

BundleSolverSummary solveBundleLevenbergMarquardt(
	std::vector<BundleCamera>& cameras, std::vector<Eigen::Vector3d>& points, const std::vector<BundleTerm>& terms,
	const PinholeIntrinsics& K, double bf, const BundleSolverOptions& o)
{
	BundleSolverSummary s;
	const detail::BundleIndex index(cameras, points.size(), terms);
	auto t0 = std::chrono::steady_clock::now();
	detail::BundleLinearization lin;
	const bool usable = lin.evaluate(index, cameras, points, terms, K, bf);
	s.evaluationSeconds += secondsSince(t0);
	if (!usable)
	{
		s.usable = false;
		s.initialCost = s.finalCost = std::numeric_limits<double>::infinity();
		return s;
	}
	s.initialCost = s.finalCost = lin.cost;
	t0 = std::chrono::steady_clock::now();
	detail::ReducedCameraSystem system(index, terms);
	s.linearSolverSeconds += secondsSince(t0);
	detail::TrustRegion region(o.initialTrustRegionRadius);
	Eigen::VectorXd dc;
	std::vector<Eigen::Vector3d> dp;
	while (s.iterations < o.maxIterations && lin.gradientMaxNorm() > o.gradientTolerance)
	{
		s.iterations++;
		t0 = std::chrono::steady_clock::now();
		const bool solved = system.solve(lin, [&](double d) { return region.damping(d); }, dc, dp);
		s.linearSolverSeconds += secondsSince(t0);
		if (!solved)
		{
			// As Ceres after a failed linear solve: a smaller trust region.
			if (!region.shrink()) break;
			continue;
		}
		if (stepNorm(dc, dp) <= o.parameterTolerance * (parameterNorm(index, cameras, points) + o.parameterTolerance)) break;
		t0 = std::chrono::steady_clock::now();
		Candidate x = stepped(index, cameras, points, dc, dp);
		const double candidate = costAt(index, x, terms, K, bf);
		s.evaluationSeconds += secondsSince(t0);
		// Stop when the cost no longer changes (the last step is not taken, as in Ceres).
		if (std::abs(lin.cost - candidate) <= o.functionTolerance * lin.cost) break;
		const double modelDecrease = -lin.modelChange(index, terms, dc, dp);
		if (detail::TrustRegion::accepts(lin.cost - candidate, modelDecrease))
		{
			region.grow((lin.cost - candidate) / modelDecrease);
			cameras = std::move(x.cameras);
			points = std::move(x.points);
			s.successfulIterations++;
			t0 = std::chrono::steady_clock::now();
			lin.evaluate(index, cameras, points, terms, K, bf);
			s.evaluationSeconds += secondsSince(t0);
			s.finalCost = lin.cost;
		}
		else if (!region.shrink())
			break;
	}
	return s;
}

}  // namespace keygrid::sfm
