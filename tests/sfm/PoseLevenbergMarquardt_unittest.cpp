// The dedicated pose solver against closed forms and against Ceres solving the same problem
// (autodiff residuals, EigenQuaternionManifold, HuberLoss): an independent implementation.
#include <gtest/gtest.h>

#include "CeresPoseReference.h"

using namespace keygrid::sfm;
using namespace keygrid::sfm::test;

namespace pose_levenberg_marquardt_unittest
{
namespace
{
PoseSolverOptions tight()
{
	PoseSolverOptions o;
	o.maxIterations = 200;
	o.functionTolerance = o.gradientTolerance = o.parameterTolerance = 1e-14;
	return o;
}

double rotationAngle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) { return Eigen::AngleAxisd(a.transpose() * b).angle(); }

void perturb(Eigen::Matrix3d& R, Eigen::Vector3d& t)
{
	R = Eigen::AngleAxisd(0.06, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix() * R;
	t += Eigen::Vector3d(0.05, -0.04, 0.06);
}
}  // namespace

TEST(PoseLevenbergMarquardt, RecoversTheExactPoseFromExactData)
{
	const auto p = makeProblem(150, 0.0, 0, 0.0, 1);
	Eigen::Matrix3d R = p.R;
	Eigen::Vector3d t = p.t;
	perturb(R, t);
	const auto s = solvePoseLevenbergMarquardt(R, t, p.terms, K, kBf, tight());
	EXPECT_TRUE(s.usable);
	EXPECT_GT(s.initialCost, 1.0);
	EXPECT_LT(s.finalCost, 1e-16);
	EXPECT_LT(rotationAngle(R, p.R), 1e-10);
	EXPECT_LT((t - p.t).norm(), 1e-10);
}

TEST(PoseLevenbergMarquardt, ReachesCeresOptimumOfTheRobustCost)
{
	// Noise, 10 % gross outliers and a Huber loss: the optimum is not the true pose, so the
	// comparison is with Ceres minimising the same cost from the same start.
	for (const double delta : {0.0, std::sqrt(5.991)})
	{
		const auto p = makeProblem(300, 0.7, 30, delta, 2);
		Eigen::Matrix3d R = p.R, Rc;
		Eigen::Vector3d t = p.t, tc;
		perturb(R, t);
		Rc = R;
		tc = t;
		const auto s = solvePoseLevenbergMarquardt(R, t, p.terms, K, kBf, tight());
		const double ceresCost = solveWithCeres(Rc, tc, p.terms, 200, 1e-14);
		EXPECT_NEAR(s.finalCost, ceresCost, 1e-9 * ceresCost) << "delta " << delta;
		EXPECT_LT(rotationAngle(R, Rc), 1e-8) << "delta " << delta;
		EXPECT_LT((t - tc).norm(), 1e-8) << "delta " << delta;
	}
}

TEST(PoseLevenbergMarquardt, ReportsTheHuberCostInClosedForm)
{
	// One observation 5 px off in u at the true pose, no depth: |r| = 5; Huber threshold 2:
	// rho = 2 * 2 * 5 - 4 = 16, cost = rho / 2 = 8. Zero iterations: the cost at the start.
	auto p = makeProblem(1, 0.0, 0, 2.0, 3);
	p.terms[0].uv.x() += 5.0 / p.terms[0].invSigma;
	p.terms[0].disparity = 0;
	Eigen::Matrix3d R = p.R;
	Eigen::Vector3d t = p.t;
	PoseSolverOptions o;
	o.maxIterations = 0;
	const auto s = solvePoseLevenbergMarquardt(R, t, p.terms, K, kBf, o);
	EXPECT_NEAR(s.initialCost, 8.0, 1e-9);
	double sq = 0;
	ASSERT_TRUE(poseResidualSquaredNorm(R, t, p.terms[0], K, kBf, sq));
	EXPECT_NEAR(sq, 25.0, 1e-9);
	p.terms[0].huberDelta = 0;  // plain least squares: |r|^2 / 2
	EXPECT_NEAR(solvePoseLevenbergMarquardt(R, t, p.terms, K, kBf, o).initialCost, 12.5, 1e-9);
}

TEST(PoseLevenbergMarquardt, APointBehindTheCameraAtTheStartLeavesThePoseAlone)
{
	auto p = makeProblem(20, 0.0, 0, 0.0, 4);
	p.terms[0].p_world = p.R.transpose() * (Eigen::Vector3d(0.1, 0.1, -1.0) - p.t);
	Eigen::Matrix3d R = p.R;
	Eigen::Vector3d t = p.t;
	perturb(R, t);
	const Eigen::Matrix3d R0 = R;
	const Eigen::Vector3d t0 = t;
	double sq = 0;
	EXPECT_FALSE(poseResidualSquaredNorm(R, t, p.terms[0], K, kBf, sq));
	const auto s = solvePoseLevenbergMarquardt(R, t, p.terms, K, kBf, tight());
	EXPECT_FALSE(s.usable);
	EXPECT_EQ(s.iterations, 0);
	EXPECT_EQ(R, R0);
	EXPECT_EQ(t, t0);
}
}  // namespace pose_levenberg_marquardt_unittest
