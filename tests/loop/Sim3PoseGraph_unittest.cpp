/** The Sim(3) pose graph of monocular maps: the similarity type, the residual against closed
 * forms and central differences, exact and scale-drifting loops, and bad input. */
#include <ceres/cost_function.h>
#include <gtest/gtest.h>
#include <keygrid/loop/RelativeSim3Error.h>
#include <keygrid/loop/Sim3PoseGraph.h>

#include <cmath>
#include <complex>
#include <random>

using namespace keygrid::loop;

namespace
{
Eigen::Quaterniond rotation(const Eigen::Vector3d& rotVec)
{
	if (rotVec.norm() == 0) return Eigen::Quaterniond::Identity();
	return Eigen::Quaterniond(Eigen::AngleAxisd(rotVec.norm(), rotVec.normalized()));
}

Sim3 makeSim3(const Eigen::Vector3d& rotVec, const Eigen::Vector3d& t, double s) { return Sim3{rotation(rotVec), t, s}; }

/** S composed with a random similarity: rotation and translation N(0, sigma) per axis, log-scale N(0, sigmaLogS). */
Sim3 perturbed(const Sim3& S, double sigmaT, double sigmaR, double sigmaLogS, std::mt19937_64& rng)
{
	std::normal_distribution<double> g(0.0, 1.0);
	const Eigen::Vector3d dr(sigmaR * g(rng), sigmaR * g(rng), sigmaR * g(rng));
	const Eigen::Vector3d dt(sigmaT * g(rng), sigmaT * g(rng), sigmaT * g(rng));
	return S * makeSim3(dr, dt, std::exp(sigmaLogS * g(rng)));
}

double angleBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) { return a.angularDistance(b); }

Eigen::Matrix<double, 7, 1> residual(const RelativeSim3Error& f, const Sim3& Sa, const Sim3& Sb)
{
	const double la = std::log(Sa.s), lb = std::log(Sb.s);
	Eigen::Matrix<double, 7, 1> r;
	EXPECT_TRUE(f(Sa.t.data(), Sa.q.coeffs().data(), &la, Sb.t.data(), Sb.q.coeffs().data(), &lb, r.data()));
	return r;
}

/** n keyframes on a circle of radius 5 m with a vertical wave, some roll/pitch and a scale
 * varying between e^-0.3 and e^0.3. */
std::vector<Sim3> wavyCircleTruth(int n)
{
	std::vector<Sim3> gt;
	for (int i = 0; i < n; ++i)
	{
		const double th = 2 * M_PI * i / n;
		const Eigen::Quaterniond q(
			Eigen::AngleAxisd(th + M_PI / 2, Eigen::Vector3d::UnitZ()) *
			Eigen::AngleAxisd(0.1 * std::sin(2 * th), Eigen::Vector3d::UnitX()) *
			Eigen::AngleAxisd(0.05 * std::cos(3 * th), Eigen::Vector3d::UnitY()));
		gt.push_back(Sim3{q, Eigen::Vector3d(5 * std::cos(th), 5 * std::sin(th), 0.3 * std::sin(3 * th)), std::exp(0.3 * std::sin(th))});
	}
	return gt;
}
}  // namespace

TEST(Sim3, ComposeInverseAndActOnAPoint)
{
	// A = (2, Rz(90 deg), (1, 0, 0)): x = (1, 0, 0) -> 2 (0, 1, 0) + (1, 0, 0) = (1, 2, 0).
	const Sim3 A = makeSim3({0, 0, M_PI / 2}, {1, 0, 0}, 2.0);
	const Eigen::Vector3d x(1, 0, 0);
	EXPECT_LT((A * x - Eigen::Vector3d(1, 2, 0)).norm(), 1e-15);
	// B = (0.5, Rx(90 deg), (0, 0, 1)): x -> (0.5, 0, 1); then A: 2 (0, 0.5, 1) + (1, 0, 0).
	const Sim3 B = makeSim3({M_PI / 2, 0, 0}, {0, 0, 1}, 0.5);
	EXPECT_LT(((A * B) * x - Eigen::Vector3d(1, 1, 2)).norm(), 1e-15);
	EXPECT_NEAR((A * B).s, 1.0, 1e-15);
	EXPECT_LT((A.inverse() * (A * x) - x).norm(), 1e-15);
	const Sim3 I = A * A.inverse();
	EXPECT_NEAR(I.s, 1.0, 1e-15);
	EXPECT_LT(I.t.norm(), 1e-15);
	EXPECT_LT(angleBetween(I.q, Eigen::Quaterniond::Identity()), 1e-7);
	// The rigid part is the camera pose: same centre and orientation, scale dropped.
	EXPECT_LT((A.rigid() * x - Eigen::Vector3d(1, 1, 0)).norm(), 1e-15);
}

TEST(RelativeSim3Error, ClosedFormResiduals)
{
	// b is where the measurement puts it, then moved by dS = (e^0.02, Rz(0.1), (0.03, 0, 0))
	// in its own frame: the residual is [t_d; 2 vec(q_d); log s_d] of that dS.
	const Sim3 Sa = makeSim3({0.1, -0.2, 0.3}, {1, 2, 3}, 1.7);
	const Sim3 Sab = makeSim3({0.05, 0.02, -0.4}, {0.5, -0.1, 0.2}, 0.8);
	const Sim3 Sb = Sa * Sab * makeSim3({0, 0, 0.1}, {0.03, 0, 0}, std::exp(0.02));
	const RelativeSim3Error f(Sab, Matrix7d::Identity());
	const Eigen::Matrix<double, 7, 1> r = residual(f, Sa, Sb);
	Eigen::Matrix<double, 7, 1> expected;
	expected << 0.03, 0, 0, 0, 0, 2 * std::sin(0.05), 0.02;
	EXPECT_LT((r - expected).norm(), 1e-12) << r.transpose();
	// -q is the same rotation: same residual.
	Sim3 SbNeg = Sb;
	SbNeg.q.coeffs() = -Sb.q.coeffs();
	EXPECT_LT((residual(f, Sa, SbNeg) - r).norm(), 1e-12);
	// The information whitens it: Omega = diag(4, ...) doubles e_x.
	Matrix7d sqrtInfo = Matrix7d::Identity();
	sqrtInfo(0, 0) = 2;
	EXPECT_NEAR(residual(RelativeSim3Error(Sab, sqrtInfo), Sa, Sb)(0), 0.06, 1e-12);
}

TEST(RelativeSim3Error, AutoDiffJacobiansMatchFiniteDifferences)
{
	std::mt19937_64 rng(4);
	std::normal_distribution<double> g(0.0, 1.0);
	Matrix7d A;
	for (int i = 0; i < 49; ++i) A(i / 7, i % 7) = g(rng);
	const Matrix7d sqrtInfo = (A * A.transpose() + Matrix7d::Identity()).llt().matrixU();
	const Sim3 Sab = makeSim3({0.2, 0.1, -0.3}, {0.4, 0.3, -0.2}, 1.3);
	std::unique_ptr<ceres::CostFunction> cost(RelativeSim3Error::Create(Sab, sqrtInfo));
	for (int trial = 0; trial < 5; ++trial)
	{
		const Sim3 Sa = makeSim3({g(rng), g(rng), g(rng)}, {g(rng), g(rng), g(rng)}, std::exp(0.5 * g(rng)));
		const Sim3 Sb = perturbed(Sa * Sab, 0.1, 0.1, 0.1, rng);
		std::vector<std::vector<double>> x = {
			{Sa.t.x(), Sa.t.y(), Sa.t.z()}, {Sa.q.x(), Sa.q.y(), Sa.q.z(), Sa.q.w()}, {std::log(Sa.s)},
			{Sb.t.x(), Sb.t.y(), Sb.t.z()}, {Sb.q.x(), Sb.q.y(), Sb.q.z(), Sb.q.w()}, {std::log(Sb.s)}};
		const auto residuals = [&](const std::vector<std::vector<double>>& at, double* r, double** jac) {
			const double* params[6] = {at[0].data(), at[1].data(), at[2].data(), at[3].data(), at[4].data(), at[5].data()};
			return cost->Evaluate(params, r, jac);
		};
		double r[7];
		std::vector<std::vector<double>> J(6);
		double* jac[6];
		for (std::size_t b = 0; b < 6; ++b)
		{
			J[b].resize(7 * x[b].size());
			jac[b] = J[b].data();
		}
		ASSERT_TRUE(residuals(x, r, jac));
		// Central differences on every ambient parameter (quaternions included: the cost is
		// defined for any quaternion, the manifold only restricts where it is evaluated).
		const double h = 1e-6;
		for (std::size_t b = 0; b < 6; ++b)
			for (std::size_t k = 0; k < x[b].size(); ++k)
			{
				auto xp = x, xm = x;
				xp[b][k] += h;
				xm[b][k] -= h;
				double rp[7], rm[7];
				ASSERT_TRUE(residuals(xp, rp, nullptr));
				ASSERT_TRUE(residuals(xm, rm, nullptr));
				for (std::size_t i = 0; i < 7; ++i)
				{
					const double fd = (rp[i] - rm[i]) / (2 * h);
					const double ad = J[b][i * x[b].size() + k];
					EXPECT_NEAR(ad, fd, 1e-5 * std::max(1.0, std::abs(fd))) << "block " << b << " param " << k << " residual " << i;
				}
			}
	}
}

TEST(Sim3PoseGraph, ExactEdgesFromAPerturbedStartConvergeToTheTruth)
{
	// Noise-free edges (odometry, covisibility k -> k+3, loop) between keyframes of different
	// scales, start perturbed by ~0.1 m / ~0.03 rad / ~5 % scale, the middle keyframe held fixed
	// at its true value (as for a loop's matched keyframe): the optimum is the truth itself, and
	// Gauss-Newton converges quadratically to it.
	const auto gt = wavyCircleTruth(40);
	const std::size_t n = gt.size(), fixedId = n / 2;
	std::mt19937_64 rng(9);
	Sim3PoseGraph g;
	for (std::size_t i = 0; i < n; ++i) g.addVertex(i, i == fixedId ? gt[i] : perturbed(gt[i], 0.1, 0.03, 0.05, rng));
	g.setFixed(fixedId);
	for (std::size_t i = 0; i < n; ++i)
	{
		const std::size_t j = (i + 1) % n;
		g.addEdge(Sim3PoseGraphEdge{i, j, gt[i].inverse() * gt[j], Matrix7d::Identity(), j == 0 ? EdgeKind::Loop : EdgeKind::Odometry});
		if (i + 3 < n) g.addEdge(Sim3PoseGraphEdge{i, i + 3, gt[i].inverse() * gt[i + 3], Matrix7d::Identity(), EdgeKind::Covisibility});
	}
	double before = 0;
	for (std::size_t i = 0; i < n; ++i) before = std::max(before, (g.pose(i).t - gt[i].t).norm());
	const auto sum = g.optimize();
	ASSERT_TRUE(sum.usable) << sum.message;
	EXPECT_NE(sum.linearSolver.find("SPARSE_NORMAL_CHOLESKY"), std::string::npos);
	EXPECT_GT(before, 0.1);
	// Ceres stops once a step is below parameter_tolerance (1e-8) relative to |x| (~30 m here),
	// without taking it: positions are right to ~1e-9 relative to the 5 m of the circle.
	for (std::size_t i = 0; i < n; ++i)
	{
		EXPECT_LT((g.pose(i).t - gt[i].t).norm(), 5 * 1e-9) << i;
		EXPECT_LT(angleBetween(g.pose(i).q, gt[i].q), 1e-9) << i;
		EXPECT_NEAR(std::log(g.pose(i).s), std::log(gt[i].s), 1e-9) << i;
	}
	EXPECT_LT(g.chi2(), 1e-18);
	ASSERT_EQ(sum.corrections.size(), n);
	EXPECT_EQ(sum.corrections[fixedId].S_world_kf_new.t, gt[fixedId].t);
}

TEST(Sim3PoseGraph, LoopClosureUndoesAScaleDrift)
{
	// Truth: n keyframes at unit scale on a circle of radius 5 m, one step L = 2 R sin(pi / n)
	// apart. A monocular map whose scale shrinks by d per keyframe: its step k -> k+1 is
	// c_k = d^k times the true one, and its points near keyframe k are c_k times their true
	// size. The graph, as loop closing would build it:
	// * vertices: the drifted poses at unit scale (rotations exact, no rotation noise);
	// * odometry edges k -> k+1: their relative poses at unit relative scale,
	//   (1, R_k^T R_k+1, c_k R_k^T (p_k+1 - p_k));
	// * the loop edge n-1 -> 0: the similarity loop detection measures between the map near both
	//   ends, S*_n-1^-1 S*_0 with S*_k = (1 / c_k, R_k, p_k) (true pose, scale undoing the drift).
	const int n = 40;
	const double R = 5, d = 0.99, lambda = -std::log(d), dth = 2 * M_PI / n, L = 2 * R * std::sin(dth / 2);
	std::vector<Sim3> truth, drifted;
	for (int k = 0; k < n; ++k)
	{
		const double th = k * dth;
		truth.push_back(makeSim3({0, 0, th + M_PI / 2}, {R * std::cos(th), R * std::sin(th), 0}, std::pow(d, -k)));
		Sim3 S = truth.back();
		S.s = 1;
		if (k > 0) S.t = drifted.back().t + std::pow(d, k - 1) * (truth[k].t - truth[k - 1].t);
		drifted.push_back(S);
	}
	Sim3PoseGraph g;
	for (int k = 0; k < n; ++k) g.addVertex(k, drifted[k]);
	for (int k = 0; k + 1 < n; ++k)
		g.addEdge(Sim3PoseGraphEdge{KeyFrameId(k), KeyFrameId(k + 1), drifted[k].inverse() * drifted[k + 1], Matrix7d::Identity(), EdgeKind::Odometry});
	g.addEdge(Sim3PoseGraphEdge{KeyFrameId(n - 1), 0, truth[n - 1].inverse() * truth[0], Matrix7d::Identity(), EdgeKind::Loop});

	// Before: the end point is off by sum_k (1 - d^k) (p_k+1 - p_k); the steps turn by dth
	// each, so in the complex plane the sum is L |sum_k (1 - d^k) z^k|, z = e^(i dth), two
	// geometric series.
	const std::complex<double> z = std::polar(1.0, dth);
	const double endBefore = L * std::abs((1.0 - std::pow(z, n - 1)) / (1.0 - z) - (1.0 - std::pow(d * z, n - 1)) / (1.0 - d * z));
	EXPECT_NEAR((drifted[n - 1].t - truth[n - 1].t).norm(), endBefore, 1e-9);
	EXPECT_GT(endBefore, 1.6);

	const auto sum = g.optimize();
	ASSERT_TRUE(sum.usable) << sum.message;

	// After: the S*_k meet every edge but the odometry edges' unit relative scale, whose
	// log-scales add up to 0 around the cycle where the loop says (n-1) lambda. With unit
	// information the n edges of the cycle share that misfit: in the scale-only problem each
	// takes (n-1) lambda / n, so keyframe k's log-scale falls short of the truth's k lambda
	// by k lambda / n. Its steps are then too short by that fraction at most, which sums to
	// B = sum_k<n-1 k lambda L / n = (n-1)(n-2)/2 lambda L / n at the end point; the loop
	// edge's translation pulls the end back towards the truth, so no keyframe is further off.
	const double bound = (n - 1) * (n - 2) / 2.0 * lambda * L / n;
	double worst = 0;
	for (int k = 0; k < n; ++k) worst = std::max(worst, (g.pose(k).t - truth[k].t).norm());
	std::cout << "scale drift " << d << "/keyframe: end point off by " << endBefore << " m before, worst keyframe "
			  << worst << " m after (bound " << bound << " m), last scale " << g.pose(n - 1).s << " (truth "
			  << truth[n - 1].s << "), " << sum.iterations << " iterations\n";
	EXPECT_LT(worst, bound);
	EXPECT_LT(bound, 0.1 * endBefore);

	// Scales follow the drift: s_0 = 1 (the fixed gauge), increasing, and every keyframe's
	// log-scale recovers its drift k lambda up to the loop edge's share (n-1) lambda / n of the
	// misfit. The scale-only argument predicts log s_n-1 = (n-1)^2 lambda / n at the end, where
	// the loop edge pins the translations: it must hold there within 5 % of that share.
	const double loopShare = (n - 1) * lambda / n;
	EXPECT_EQ(g.pose(0).s, 1.0);
	for (int k = 1; k < n; ++k)
	{
		EXPECT_GT(g.pose(k).s, g.pose(k - 1).s) << k;
		EXPECT_NEAR(std::log(g.pose(k).s), k * lambda, loopShare) << k;
	}
	EXPECT_NEAR(std::log(g.pose(n - 1).s), (n - 1) * loopShare, 0.05 * loopShare);
	// Rotations were exact and stay so up to what the compromise in translation needs.
	for (int k = 0; k < n; ++k) EXPECT_LT(angleBetween(g.pose(k).q, truth[k].q), 0.01) << k;
}

// A metric map (setScalesFixed): the loop of the scale-drift test above, but measured at unit
// scale, as a loop between two metric ends is. The keyframes move towards the truth and no scale
// changes, where the free graph spreads a scale change over the loop to meet the loop's
// translation.
TEST(Sim3PoseGraph, WithFixedScalesALoopMovesKeyFramesButRescalesNone)
{
	const int n = 40;
	const double R = 5, d = 0.99, dth = 2 * M_PI / n;
	std::vector<Sim3> truth, drifted;
	for (int k = 0; k < n; ++k)
	{
		const double th = k * dth;
		truth.push_back(makeSim3({0, 0, th + M_PI / 2}, {R * std::cos(th), R * std::sin(th), 0}, 1.0));
		Sim3 S = truth.back();
		if (k > 0) S.t = drifted.back().t + std::pow(d, k - 1) * (truth[k].t - truth[k - 1].t);
		drifted.push_back(S);
	}
	for (const bool fixed : {true, false})
	{
		SCOPED_TRACE(fixed ? "fixed scales" : "free scales");
		Sim3PoseGraph g;
		g.setScalesFixed(fixed);
		for (int k = 0; k < n; ++k) g.addVertex(k, drifted[k]);
		for (int k = 0; k + 1 < n; ++k)
			g.addEdge(Sim3PoseGraphEdge{KeyFrameId(k), KeyFrameId(k + 1), drifted[k].inverse() * drifted[k + 1], Matrix7d::Identity(), EdgeKind::Odometry});
		g.addEdge(Sim3PoseGraphEdge{KeyFrameId(n - 1), 0, truth[n - 1].inverse() * truth[0], Matrix7d::Identity(), EdgeKind::Loop});
		const double before = (drifted[n - 1].t - truth[n - 1].t).norm();
		const auto sum = g.optimize();
		ASSERT_TRUE(sum.usable) << sum.message;
		EXPECT_LT((g.pose(n - 1).t - truth[n - 1].t).norm(), 0.5 * before);
		double furthestScale = 0;
		for (int k = 0; k < n; ++k) furthestScale = std::max(furthestScale, std::abs(g.pose(k).s - 1.0));
		if (fixed)
			EXPECT_EQ(furthestScale, 0.0);
		else
			EXPECT_GT(furthestScale, 1e-3);
	}
}

TEST(Sim3PoseGraph, RigidCorrectionMovesPointsLikeTheSimilarity)
{
	// A keyframe tracked at unit scale, corrected to scale 1.3 with a new pose: a point seen at
	// x_kf in its camera frame moves to 1.3 R_new x_kf + t_new.
	const Eigen::Quaterniond qOld = rotation({0.1, 0.2, 0.3}), qNew = rotation({-0.2, 0.0, 0.5});
	const Eigen::Vector3d tOld(1, 2, 3), tNew(0.5, 2.5, 2.0), x_kf(0.3, -0.2, 2.0);
	const Sim3Correction c{7, Sim3{qOld, tOld, 1.0}, Sim3{qNew, tNew, 1.3}};
	const Eigen::Vector3d p_old = qOld * x_kf + tOld;
	const Eigen::Vector3d expected = 1.3 * (qNew * x_kf) + tNew;
	EXPECT_LT((movePointWithKeyFrame(p_old, c.S_world_kf_old, c.S_world_kf_new) - expected).norm(), 1e-12);

	// The SE(3) form: the pose is the rigid part (the camera centre is t_new), and the point's
	// camera coordinates grow by s_new / s_old.
	const RigidCorrection rc = toRigidCorrection(c);
	EXPECT_EQ(rc.pose.id, 7u);
	EXPECT_DOUBLE_EQ(rc.pointScale, 1.3);
	EXPECT_LT((rc.pose.T_world_kf_new.translation() - tNew).norm(), 1e-15);
	EXPECT_LT((rc.pose.T_world_kf_new * (rc.pointScale * (rc.pose.T_world_kf_old.inverse() * p_old)) - expected).norm(), 1e-12);

	// A keyframe already corrected once (s_old = 0.8): its points are 0.8 x_kf in its rigid
	// frame, and they grow by 1.3 / 0.8.
	const Sim3Correction c2{8, Sim3{qOld, tOld, 0.8}, Sim3{qNew, tNew, 1.3}};
	const Eigen::Vector3d p2 = c2.S_world_kf_old * x_kf;
	const RigidCorrection rc2 = toRigidCorrection(c2);
	EXPECT_DOUBLE_EQ(rc2.pointScale, 1.3 / 0.8);
	EXPECT_LT((rc2.pose.T_world_kf_new * (rc2.pointScale * (rc2.pose.T_world_kf_old.inverse() * p2)) - expected).norm(), 1e-12);
	EXPECT_LT((movePointWithKeyFrame(p2, c2.S_world_kf_old, c2.S_world_kf_new) - expected).norm(), 1e-12);
}

TEST(Sim3PoseGraph, RejectsBadInput)
{
	auto expectThrowMentioning = [](const auto& f, const std::string& text) {
		try
		{
			f();
			ADD_FAILURE() << "expected std::invalid_argument mentioning \"" << text << "\"";
		}
		catch (const std::invalid_argument& e)
		{
			EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
		}
	};
	Sim3PoseGraph g;
	g.addVertex(1, Sim3{});
	g.addVertex(2, Sim3{});
	expectThrowMentioning([&] { g.addVertex(3, Sim3{Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero(), 0.0}); }, "vertex 3: scale 0");
	expectThrowMentioning([&] { g.addVertex(4, Sim3{Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero(), -2.0}); }, "vertex 4: scale -2");
	expectThrowMentioning([&] { g.addVertex(5, Sim3{Eigen::Quaterniond(0, 0, 0, 0), Eigen::Vector3d::Zero(), 1.0}); }, "vertex 5: rotation");
	EXPECT_FALSE(g.hasVertex(3));
	expectThrowMentioning([&] { g.addEdge(Sim3PoseGraphEdge{1, 9, Sim3{}, Matrix7d::Identity(), EdgeKind::Odometry}); }, "unknown vertex 9");
	expectThrowMentioning([&] { g.addEdge(Sim3PoseGraphEdge{2, 2, Sim3{}, Matrix7d::Identity(), EdgeKind::Odometry}); }, "self edge on vertex 2");
	expectThrowMentioning(
		[&] { g.addEdge(Sim3PoseGraphEdge{1, 2, Sim3{Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero(), -1.0}, Matrix7d::Identity(), EdgeKind::Loop}); },
		"edge 1->2: scale -1");
	expectThrowMentioning([&] { g.addEdge(Sim3PoseGraphEdge{1, 2, Sim3{}, -Matrix7d::Identity(), EdgeKind::Odometry}); }, "not symmetric positive definite");
	expectThrowMentioning([&] { g.setFixed(6); }, "unknown vertex 6");
	EXPECT_TRUE(g.edges().empty());
	PoseGraphOptions o;
	o.maxIterations = 0;
	expectThrowMentioning([&] { g.optimize(o); }, "max_iterations");
}
