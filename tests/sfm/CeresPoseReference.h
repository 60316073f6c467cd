#pragma once
// Synthetic one-camera pose problems and Ceres solving them (autodiff residuals,
// EigenQuaternionManifold, HuberLoss): the independent reference for the dedicated pose solver
// in its unit test and its benchmark.
#include <keygrid/sfm/PoseLevenbergMarquardt.h>
#include <keygrid/sfm/RgbdReprojectionCost.h>

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace keygrid::sfm::test
{
inline const PinholeIntrinsics K{517.3, 516.5, 318.6, 255.3};
inline constexpr double kBf = 40.0, kDisparitySigma = 0.25;

struct Problem
{
	Eigen::Matrix3d R;  //!< true R_cam_world
	Eigen::Vector3d t;  //!< true t_cam_world
	std::vector<PoseResidualTerm> terms;
};

/** Points in front of the camera; every third without depth; `outliers` moved 30 px. */
inline Problem makeProblem(int n, double pixelNoise, int outliers, double huberDelta, unsigned seed)
{
	Problem p;
	p.R = Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.3, -0.8, 0.5).normalized()).toRotationMatrix();
	p.t = Eigen::Vector3d(0.2, -0.5, 1.1);
	std::mt19937 g(seed);
	std::uniform_real_distribution<double> uu(20, 620), vv(20, 460), dd(0.7, 4.5);
	std::normal_distribution<double> px(0, pixelNoise);
	for (int i = 0; i < n; i++)
	{
		const double u = uu(g), v = vv(g), d = dd(g);
		const Eigen::Vector3d pc((u - K.cx) / K.fx * d, (v - K.cy) / K.fy * d, d);
		PoseResidualTerm term;
		term.p_world = p.R.transpose() * (pc - p.t);
		term.uv = Eigen::Vector2d(u + px(g), v + px(g)) + (i < outliers ? Eigen::Vector2d(30, -30) : Eigen::Vector2d::Zero());
		term.invSigma = 1.0 / std::pow(1.2, i % 4);
		if (i % 3 != 0)
		{
			term.disparity = kBf / (d * (1.0 + 0.002 * px(g)));
			term.invSigmaDisparity = 1.0 / kDisparitySigma;
		}
		term.huberDelta = huberDelta;
		p.terms.push_back(term);
	}
	return p;
}

/** The same residual as the solver's, for Ceres' autodiff (q_cam_world as x, y, z, w). */
struct ReferenceCost
{
	explicit ReferenceCost(const PoseResidualTerm& t) : term(t) {}
	template <typename T>
	bool operator()(const T* q, const T* t, T* r) const
	{
		const T p[3] = {T(term.p_world.x()), T(term.p_world.y()), T(term.p_world.z())};
		T u, v, ur;
		if (!projectRgbd(q, t, p, K, kBf, u, v, ur)) return false;
		r[0] = (T(term.uv.x()) - u) * T(term.invSigma);
		r[1] = (T(term.uv.y()) - v) * T(term.invSigma);
		r[2] = term.disparity > 0 ? (T(term.disparity) - (u - ur)) * T(term.invSigmaDisparity) : T(0.0);
		return true;
	}
	PoseResidualTerm term;
};

/** Ceres' optimum of the same robust cost from (R, t) (DENSE_QR, like the former inner solve
 * of optimizePose); returns its final cost. */
inline double solveWithCeres(
	Eigen::Matrix3d& R, Eigen::Vector3d& t, const std::vector<PoseResidualTerm>& terms, int maxIterations, double tolerance)
{
	Eigen::Quaterniond qe(R);
	double q[4] = {qe.x(), qe.y(), qe.z(), qe.w()}, tv[3] = {t.x(), t.y(), t.z()};
	ceres::Problem problem;
	problem.AddParameterBlock(q, 4, new ceres::EigenQuaternionManifold());
	problem.AddParameterBlock(tv, 3);
	for (const auto& term : terms)
		problem.AddResidualBlock(
			new ceres::AutoDiffCostFunction<ReferenceCost, 3, 4, 3>(new ReferenceCost(term)),
			term.huberDelta > 0 ? new ceres::HuberLoss(term.huberDelta) : nullptr, q, tv);
	ceres::Solver::Options so;
	so.linear_solver_type = ceres::DENSE_QR;
	so.max_num_iterations = maxIterations;
	so.function_tolerance = tolerance;
	so.gradient_tolerance = std::min(tolerance, 1e-10);
	so.parameter_tolerance = std::min(tolerance, 1e-8);
	so.logging_type = ceres::SILENT;
	ceres::Solver::Summary summary;
	ceres::Solve(so, &problem, &summary);
	R = Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized().toRotationMatrix();
	t = Eigen::Vector3d(tv[0], tv[1], tv[2]);
	return summary.final_cost;
}

}  // namespace keygrid::sfm::test
