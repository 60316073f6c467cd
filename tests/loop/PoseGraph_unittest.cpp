#include <gtest/gtest.h>
#include <keygrid/loop/PoseGraph.h>
#include <keygrid/loop/RelativePoseError.h>

#include <TestData.h>
#include <cmath>
#include <fstream>
#include <random>

using namespace keygrid::loop;

namespace
{
Eigen::Isometry3d makePose(const Eigen::Vector3d& rotVec, const Eigen::Vector3d& t)
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	if (rotVec.norm() > 0) T.linear() = Eigen::AngleAxisd(rotVec.norm(), rotVec.normalized()).toRotationMatrix();
	T.translation() = t;
	return T;
}

Eigen::Isometry3d noisy(const Eigen::Isometry3d& T, double sigmaT, double sigmaR, std::mt19937_64& rng)
{
	std::normal_distribution<double> g(0.0, 1.0);
	const Eigen::Vector3d dr(sigmaR * g(rng), sigmaR * g(rng), sigmaR * g(rng));
	const Eigen::Vector3d dt(sigmaT * g(rng), sigmaT * g(rng), sigmaT * g(rng));
	return T * makePose(dr, dt);
}

Matrix6d diagInformation(double sigmaT, double sigmaR)
{
	Matrix6d I = Matrix6d::Zero();
	I.diagonal() << 1 / (sigmaT * sigmaT), 1 / (sigmaT * sigmaT), 1 / (sigmaT * sigmaT), 1 / (sigmaR * sigmaR),
		1 / (sigmaR * sigmaR), 1 / (sigmaR * sigmaR);
	return I;
}

/** 100 poses on a circle of radius 5 m (with a vertical wave and some roll/pitch). */
std::vector<Eigen::Isometry3d> circleTruth(int n)
{
	std::vector<Eigen::Isometry3d> gt;
	for (int i = 0; i < n; ++i)
	{
		const double th = 2 * M_PI * i / n;
		Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
		T.linear() = (Eigen::AngleAxisd(th + M_PI / 2, Eigen::Vector3d::UnitZ()) *
					  Eigen::AngleAxisd(0.1 * std::sin(2 * th), Eigen::Vector3d::UnitX()) *
					  Eigen::AngleAxisd(0.05 * std::cos(3 * th), Eigen::Vector3d::UnitY()))
						 .toRotationMatrix();
		T.translation() = Eigen::Vector3d(5 * std::cos(th), 5 * std::sin(th), 0.3 * std::sin(3 * th));
		gt.push_back(T);
	}
	return gt;
}

double positionRmse(const PoseGraph& g, const std::vector<Eigen::Isometry3d>& gt)
{
	double s = 0;
	for (std::size_t i = 0; i < gt.size(); ++i) s += (g.pose(i).translation() - gt[i].translation()).squaredNorm();
	return std::sqrt(s / static_cast<double>(gt.size()));
}

/** Odometry-initialised graph with noisy odometry edges and (optionally) the loop edge n-1 -> 0. */
PoseGraph circleGraph(const std::vector<Eigen::Isometry3d>& gt, bool withLoop, std::uint64_t seed)
{
	const double sT = 0.02, sR = 0.01;
	std::mt19937_64 rng(seed);
	PoseGraph g;
	Eigen::Isometry3d T = gt[0];
	g.addVertex(0, T);
	for (std::size_t i = 1; i < gt.size(); ++i)
	{
		const Eigen::Isometry3d meas = noisy(gt[i - 1].inverse() * gt[i], sT, sR, rng);
		T = T * meas;
		g.addVertex(i, T);
		g.addEdge(PoseGraphEdge{i - 1, i, meas, diagInformation(sT, sR), EdgeKind::Odometry});
	}
	if (withLoop)
	{
		const std::size_t n = gt.size();
		const Eigen::Isometry3d meas = noisy(gt[n - 1].inverse() * gt[0], 0.005, 0.002, rng);
		g.addEdge(PoseGraphEdge{n - 1, 0, meas, diagInformation(0.005, 0.002), EdgeKind::Loop});
	}
	return g;
}
}  // namespace

TEST(RelativePoseError, ClosedFormResiduals)
{
	const Eigen::Isometry3d Ta = makePose({0.1, -0.2, 0.3}, {1, 2, 3});
	const Eigen::Isometry3d Tab = makePose({0.05, 0.02, -0.4}, {0.5, -0.1, 0.2});
	// b rotated by 0.1 rad about its own z axis and shifted by 3 cm along a's x axis.
	Eigen::Isometry3d Tb = Ta * Tab * makePose({0, 0, 0.1}, {0, 0, 0});
	Tb.translation() += Ta.linear() * Eigen::Vector3d(0.03, 0, 0);
	const Eigen::Quaterniond qa(Ta.linear()), qb(Tb.linear());
	const double pa[3] = {Ta.translation().x(), Ta.translation().y(), Ta.translation().z()};
	const double pb[3] = {Tb.translation().x(), Tb.translation().y(), Tb.translation().z()};
	const RelativePoseError f(Eigen::Quaterniond(Tab.linear()), Tab.translation(), Matrix6d::Identity());
	Eigen::Matrix<double, 6, 1> r;
	ASSERT_TRUE(f(pa, qa.coeffs().data(), pb, qb.coeffs().data(), r.data()));
	EXPECT_NEAR(r(0), 0.03, 1e-12);
	EXPECT_NEAR(r(1), 0.0, 1e-12);
	EXPECT_NEAR(r(2), 0.0, 1e-12);
	EXPECT_NEAR(r(3), 0.0, 1e-12);
	EXPECT_NEAR(r(4), 0.0, 1e-12);
	EXPECT_NEAR(r(5), 2 * std::sin(0.05), 1e-12);
	// -q is the same rotation: same residual.
	const Eigen::Quaterniond qbNeg(-qb.w(), -qb.x(), -qb.y(), -qb.z());
	Eigen::Matrix<double, 6, 1> r2;
	f(pa, qa.coeffs().data(), pb, qbNeg.coeffs().data(), r2.data());
	EXPECT_LT((r - r2).norm(), 1e-12);
}

TEST(RelativePoseError, AutoDiffJacobiansMatchFiniteDifferences)
{
	std::mt19937_64 rng(12);
	std::normal_distribution<double> g(0.0, 1.0);
	Matrix6d A;
	for (int i = 0; i < 36; ++i) A(i / 6, i % 6) = g(rng);
	const Matrix6d info = A * A.transpose() + Matrix6d::Identity();
	const Matrix6d sqrtInfo = info.llt().matrixU();
	const Eigen::Isometry3d Tab = makePose({0.2, 0.1, -0.3}, {0.4, 0.3, -0.2});
	std::unique_ptr<ceres::CostFunction> cost(
		RelativePoseError::Create(Eigen::Quaterniond(Tab.linear()), Tab.translation(), sqrtInfo));
	const RelativePoseError functor(Eigen::Quaterniond(Tab.linear()), Tab.translation(), sqrtInfo);

	for (int trial = 0; trial < 5; ++trial)
	{
		const Eigen::Isometry3d Ta = makePose({g(rng), g(rng), g(rng)}, {g(rng), g(rng), g(rng)});
		const Eigen::Isometry3d Tb = Ta * Tab * makePose({0.1 * g(rng), 0.1 * g(rng), 0.1 * g(rng)}, {0.1 * g(rng), 0, 0});
		std::vector<std::vector<double>> x(4);
		x[0] = {Ta.translation().x(), Ta.translation().y(), Ta.translation().z()};
		const Eigen::Quaterniond qa(Ta.linear()), qb(Tb.linear());
		x[1] = {qa.x(), qa.y(), qa.z(), qa.w()};
		x[2] = {Tb.translation().x(), Tb.translation().y(), Tb.translation().z()};
		x[3] = {qb.x(), qb.y(), qb.z(), qb.w()};
		const double* params[4] = {x[0].data(), x[1].data(), x[2].data(), x[3].data()};
		double r[6];
		std::vector<std::vector<double>> J = {std::vector<double>(18), std::vector<double>(24), std::vector<double>(18), std::vector<double>(24)};
		double* jac[4] = {J[0].data(), J[1].data(), J[2].data(), J[3].data()};
		ASSERT_TRUE(cost->Evaluate(params, r, jac));

		// Central differences on every ambient parameter (quaternions included: the functor
		// is defined for any quaternion, the manifold only restricts where it is evaluated).
		const double h = 1e-6;
		for (int blk = 0; blk < 4; ++blk)
			for (std::size_t k = 0; k < x[static_cast<std::size_t>(blk)].size(); ++k)
			{
				auto xp = x, xm = x;
				xp[static_cast<std::size_t>(blk)][k] += h;
				xm[static_cast<std::size_t>(blk)][k] -= h;
				double rp[6], rm[6];
				functor(xp[0].data(), xp[1].data(), xp[2].data(), xp[3].data(), rp);
				functor(xm[0].data(), xm[1].data(), xm[2].data(), xm[3].data(), rm);
				const std::size_t cols = x[static_cast<std::size_t>(blk)].size();
				for (int i = 0; i < 6; ++i)
				{
					const double fd = (rp[i] - rm[i]) / (2 * h);
					const double ad = J[static_cast<std::size_t>(blk)][static_cast<std::size_t>(i) * cols + k];
					EXPECT_NEAR(ad, fd, 1e-5 * std::max(1.0, std::abs(fd))) << "block " << blk << " param " << k << " residual " << i;
				}
			}
	}
}

TEST(PoseGraph, SyntheticLoopConvergesToGroundTruth)
{
	const auto gt = circleTruth(100);
	PoseGraph odo = circleGraph(gt, false, 1);
	PoseGraph g = circleGraph(gt, true, 1);
	const double odoRmse = positionRmse(odo, gt);
	const double before = g.chi2();
	const auto sum = g.optimize();
	ASSERT_TRUE(sum.usable) << sum.message;
	EXPECT_NE(sum.linearSolver.find("SPARSE_NORMAL_CHOLESKY"), std::string::npos);
	const double optRmse = positionRmse(g, gt);
	std::cout << "odometry RMSE " << odoRmse << " m, after loop closure " << optRmse << " m, chi2 " << before << " -> "
			  << g.chi2() << ", " << sum.iterations << " iterations (" << sum.linearSolver << ")\n";
	EXPECT_GT(odoRmse, 0.2);  // the odometry has drifted ...
	EXPECT_LT(optRmse, 0.25 * odoRmse);  // ... and closing the loop removes most of it
	EXPECT_LT(optRmse, 0.3);
	// Gauge: the first pose is held fixed.
	EXPECT_TRUE(g.pose(0).isApprox(gt[0], 1e-12));
	// At the optimum chi2 follows a chi-square law with 6 (edges - vertices + 1) = 6 DOF
	// (mean 6, 99.99 % quantile 27.9); before it was dominated by the loop edge's misfit.
	EXPECT_LT(g.chi2(), 27.9);
	EXPECT_GT(before, 1e4);
	EXPECT_EQ(sum.corrections.size(), 100u);
	EXPECT_TRUE(sum.corrections[50].T_world_kf_new.isApprox(g.pose(50)));
}

TEST(PoseGraph, ExactEdgesFromAPerturbedStartConvergeToTheTruth)
{
	// Noise-free edges (odometry + loop), initial poses perturbed by ~0.2 m / ~0.06 rad: the
	// optimum is the ground truth itself (first pose fixed at its true value).
	const auto gt = circleTruth(60);
	std::mt19937_64 rng(9);
	PoseGraph g;
	for (std::size_t i = 0; i < gt.size(); ++i) g.addVertex(i, i == 0 ? gt[0] : noisy(gt[i], 0.1, 0.03, rng));
	for (std::size_t i = 0; i < gt.size(); ++i)
	{
		const std::size_t j = (i + 1) % gt.size();
		g.addEdge(PoseGraphEdge{i, j, gt[i].inverse() * gt[j], diagInformation(0.02, 0.01), j == 0 ? EdgeKind::Loop : EdgeKind::Odometry});
	}
	const double before = positionRmse(g, gt);
	ASSERT_TRUE(g.optimize().usable);
	EXPECT_GT(before, 0.1);
	EXPECT_LT(positionRmse(g, gt), 1e-6);
	for (std::size_t i = 0; i < gt.size(); ++i)
		EXPECT_LT(Eigen::AngleAxisd(g.pose(i).linear().transpose() * gt[i].linear()).angle(), 1e-6) << i;
}

TEST(PoseGraph, RobustLossLimitsAFalseLoopEdge)
{
	const auto gt = circleTruth(100);
	PoseGraph base = circleGraph(gt, true, 2);
	// A wrong loop: claims that keyframes 25 and 75 (10 m apart) are at the same place.
	PoseGraphEdge wrong{25, 75, Eigen::Isometry3d::Identity(), diagInformation(0.005, 0.002), EdgeKind::Loop};
	PoseGraph plain = base, robust = base;
	plain.addEdge(wrong);
	robust.addEdge(wrong);
	PoseGraphOptions none;
	none.loopLoss = RobustLoss::None;
	PoseGraphOptions cauchy;
	cauchy.loopLoss = RobustLoss::Cauchy;
	cauchy.loopLossScale = 1.0;
	base.optimize();
	plain.optimize(none);
	robust.optimize(cauchy);
	const double eBase = positionRmse(base, gt), ePlain = positionRmse(plain, gt), eRobust = positionRmse(robust, gt);
	std::cout << "good graph " << eBase << " m, + false loop: plain " << ePlain << " m, Cauchy " << eRobust << " m\n";
	EXPECT_GT(ePlain, 1.0);
	EXPECT_LT(eRobust, 0.5 * ePlain);
}

TEST(PoseGraph, PointsFollowTheirKeyFrame)
{
	const Eigen::Isometry3d oldT = makePose({0.1, 0.2, 0.3}, {1, 2, 3});
	const Eigen::Isometry3d newT = makePose({-0.2, 0.0, 0.5}, {0.5, 2.5, 2.0});
	const Eigen::Vector3d p_kf(0.3, -0.2, 2.0);
	const Eigen::Vector3d moved = movePointWithKeyFrame(oldT * p_kf, oldT, newT);
	EXPECT_LT((moved - newT * p_kf).norm(), 1e-12);
}

TEST(PoseGraph, G2oRoundTrip)
{
	const auto gt = circleTruth(20);
	PoseGraph g = circleGraph(gt, true, 3);
	Matrix6d info = diagInformation(0.1, 0.05);
	info(0, 1) = info(1, 0) = 3.0;  // off-diagonal terms survive the round trip
	g.addEdge(PoseGraphEdge{2, 9, gt[2].inverse() * gt[9], info, EdgeKind::Covisibility});
	g.setFixed(5);
	const std::string path = keygrid::test::scratchDir("loop_g2o") + "/posegraph.g2o";
	g.writeG2o(path);
	PoseGraph r = PoseGraph::readG2o(path);
	ASSERT_EQ(r.numVertices(), g.numVertices());
	ASSERT_EQ(r.edges().size(), g.edges().size());
	for (const auto& [id, T] : g.poses()) EXPECT_TRUE(r.pose(id).isApprox(T, 1e-12)) << id;
	for (std::size_t i = 0; i < g.edges().size(); ++i)
	{
		const auto& a = g.edges()[i];
		const auto& b = r.edges()[i];
		EXPECT_EQ(a.a, b.a);
		EXPECT_EQ(a.b, b.b);
		EXPECT_EQ(a.kind, b.kind);
		EXPECT_TRUE(a.T_a_b.isApprox(b.T_a_b, 1e-12));
		EXPECT_TRUE(a.information.isApprox(b.information, 1e-12));
	}
	// Same graph, same optimum (vertex 5 fixed in both).
	g.optimize();
	r.optimize();
	for (const auto& [id, T] : g.poses()) EXPECT_TRUE(r.pose(id).isApprox(T, 1e-9)) << id;
	EXPECT_TRUE(g.pose(5).isApprox(r.pose(5)));

	const std::string bad = keygrid::test::scratchDir("loop_g2o_bad") + "/bad.g2o";
	{
		std::ofstream f(bad);
		f << "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nEDGE_SE3:QUAT 0 7 0 0 0 0 0 0 1\n";
	}
	try
	{
		PoseGraph::readG2o(bad);
		FAIL() << "expected an exception";
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_NE(std::string(e.what()).find("bad.g2o:2"), std::string::npos) << e.what();
	}
}

TEST(PoseGraph, RejectsBadEdges)
{
	PoseGraph g;
	g.addVertex(1, Eigen::Isometry3d::Identity());
	g.addVertex(2, Eigen::Isometry3d::Identity());
	EXPECT_THROW(g.addEdge(PoseGraphEdge{1, 3, Eigen::Isometry3d::Identity(), Matrix6d::Identity(), EdgeKind::Odometry}), std::invalid_argument);
	EXPECT_THROW(g.addEdge(PoseGraphEdge{1, 2, Eigen::Isometry3d::Identity(), -Matrix6d::Identity(), EdgeKind::Odometry}), std::invalid_argument);
	PoseGraphOptions o;
	o.maxIterations = 0;
	EXPECT_THROW(g.optimize(o), std::invalid_argument);
}
