// Pose-only refinement and PnP on synthetic correspondences with a known pose.
#include <keygrid/sfm/PnpSolver.h>
#include <keygrid/sfm/PoseOptimizer.h>
#include <keygrid/sfm/Triangulation.h>

#include <ceres/ceres.h>
#include <cmath>
#include <random>

#include "TestData.h"

using namespace keygrid::sfm;
using mrpt::poses::CPose3D;

namespace pose_optimizer_unittest
{
namespace
{
const PinholeIntrinsics K{517.3, 516.5, 318.6, 255.3};

struct Scene
{
	CPose3D T_world_cam;
	std::vector<PoseObservation> obs;
};

// Points spread in front of the camera, observed exactly (plus optional pixel noise/outliers).
Scene makeScene(int n, double pixelNoise, int outliers, unsigned seed)
{
	Scene s;
	s.T_world_cam = CPose3D(0.4, -0.3, 1.2, 0.5, -0.2, 0.3);
	std::mt19937 g(seed);
	std::uniform_real_distribution<double> uu(20, 620), vv(20, 460), dd(0.8, 4.0);
	std::normal_distribution<double> px(0, pixelNoise);
	for (int i = 0; i < n; i++)
	{
		const double u = uu(g), v = vv(g), d = dd(g);
		const double x = (u - K.cx) / K.fx * d, y = (v - K.cy) / K.fy * d;
		double wx, wy, wz;
		s.T_world_cam.composePoint(x, y, d, wx, wy, wz);
		PoseObservation o;
		o.p_world = {wx, wy, wz};
		o.uv = {u + px(g), v + px(g)};
		o.depth = d;
		o.invSigma = 1.0;
		if (i < outliers) o.uv += Eigen::Vector2d(40, -35);
		s.obs.push_back(o);
	}
	return s;
}

double poseError(const CPose3D& a, const CPose3D& b)
{
	const CPose3D d = a - b;
	return d.translation().norm() + std::abs(d.yaw()) + std::abs(d.pitch()) + std::abs(d.roll());
}
}  // namespace

TEST(PoseOptimizer, CeresConversionsRoundTrip)
{
	const CPose3D T(1.0, -2.0, 0.3, 2.5, -1.2, 0.7);
	double q[4], t[3];
	toCeres(T, q, t);
	EXPECT_NEAR(poseError(fromCeres(q, t), T), 0.0, 1e-12);
	// (q, t) is T_cam_world: it maps the camera centre to the origin.
	const Eigen::Quaterniond qe(q[3], q[0], q[1], q[2]);
	const Eigen::Vector3d c(T.x(), T.y(), T.z());
	EXPECT_NEAR((qe * c + Eigen::Vector3d(t[0], t[1], t[2])).norm(), 0.0, 1e-12);
}

TEST(PoseOptimizer, ConvergesFromAPerturbedPoseWithExactData)
{
	const auto s = makeScene(200, 0.0, 0, 1);
	CPose3D T = s.T_world_cam + CPose3D(0.05, -0.04, 0.03, 0.04, 0.03, -0.05);
	const auto r = optimizePose(T, s.obs, K);
	EXPECT_EQ(r.inliers, 200);
	EXPECT_NEAR(poseError(T, s.T_world_cam), 0.0, 1e-6);
	EXPECT_LT(r.rmsPixels, 1e-5);
}

TEST(PoseOptimizer, RejectsOutliersUnderNoise)
{
	const auto s = makeScene(300, 0.5, 60, 2);
	CPose3D T = s.T_world_cam + CPose3D(0.03, 0.02, -0.02, 0.02, -0.02, 0.01);
	const auto r = optimizePose(T, s.obs, K);
	int flagged = 0;
	for (int i = 0; i < 60; i++) flagged += !r.inlier[static_cast<std::size_t>(i)];
	EXPECT_EQ(flagged, 60);
	EXPECT_GE(r.inliers, 230);  // chi2 at 95 %: ~5 % of the 240 good ones may be cut
	EXPECT_LT((T - s.T_world_cam).translation().norm(), 2e-3);
}

TEST(PoseOptimizer, APointBehindTheCameraIsAnOutlierInsteadOfStoppingTheSolve)
{
	auto s = makeScene(200, 0.0, 0, 3);
	// A wrong association with a point 1 m behind the camera (e.g. a stale landmark).
	double wx, wy, wz;
	s.T_world_cam.composePoint(0.1, 0.1, -1.0, wx, wy, wz);
	s.obs[0].p_world = {wx, wy, wz};
	PoseOptimizerOptions o;
	o.rounds = 1;  // a single round: nothing to recover in if the first solve stops
	CPose3D T = s.T_world_cam + CPose3D(0.05, -0.04, 0.03, 0.04, 0.03, -0.05);
	const auto r = optimizePose(T, s.obs, K, o);
	EXPECT_FALSE(r.inlier[0]);
	EXPECT_EQ(r.inliers, 199);
	EXPECT_NEAR(poseError(T, s.T_world_cam), 0.0, 1e-6);
}

namespace
{
// A walker: the first `moving` observations see points that moved 8 cm (world x) since their
// landmarks were made, so the map holds them at p - 8 cm. They all agree with one wrong pose,
// T_world_cam shifted by the same 8 cm. Observations from `anchorsFrom` on are anchors.
Scene movingObjectScene(int n, int moving, std::vector<char>& isAnchor, int anchorsFrom)
{
	auto s = makeScene(n, 0.3, 0, 4);
	isAnchor.assign(static_cast<std::size_t>(n), 0);
	for (int i = 0; i < n; i++)
	{
		if (i < moving) s.obs[static_cast<std::size_t>(i)].p_world.x() -= 0.08;
		isAnchor[static_cast<std::size_t>(i)] = i >= anchorsFrom;
	}
	return s;
}
}  // namespace

TEST(PoseOptimizer, AnchoredRefinementIgnoresAMovingMajorityOfYoungLandmarks)
{
	// 300 matches: 180 on the walker (young), 40 young static points, 80 anchors. Both solvers
	// start from the pose that followed the walker, as the motion model predicts it then.
	std::vector<char> isAnchor;
	const auto s = movingObjectScene(300, 180, isAnchor, 220);
	const CPose3D followed = CPose3D(-0.08, 0, 0, 0, 0, 0) + s.T_world_cam;
	CPose3D plain = followed;
	optimizePose(plain, s.obs, K);
	EXPECT_GT((plain - s.T_world_cam).translation().norm(), 0.07);  // the majority decides

	CPose3D T = followed;
	int rejected = -1;
	const auto r = optimizePoseAnchored(T, s.obs, isAnchor, K, {}, 9.0, 30, &rejected);
	EXPECT_LT((T - s.T_world_cam).translation().norm(), 2e-3);
	EXPECT_EQ(rejected, 180);
	for (int i = 0; i < 180; i++) EXPECT_FALSE(r.inlier[static_cast<std::size_t>(i)]) << i;
	int youngStatic = 0;
	for (int i = 180; i < 220; i++) youngStatic += r.inlier[static_cast<std::size_t>(i)];
	EXPECT_GE(youngStatic, 36);  // the young static points stay (chi2 at 95 %)
}

TEST(PoseOptimizer, AnchoredRefinementEqualsThePlainOneWithoutMovingPointsOrAnchors)
{
	std::vector<char> isAnchor;
	const auto s = movingObjectScene(300, 0, isAnchor, 200);
	const CPose3D start = s.T_world_cam + CPose3D(0.02, -0.01, 0.01, 0.01, 0.02, -0.01);
	CPose3D plain = start, anchored = start;
	const auto rp = optimizePose(plain, s.obs, K);
	int rejected = -1;
	const auto ra = optimizePoseAnchored(anchored, s.obs, isAnchor, K, {}, 9.0, 30, &rejected);
	EXPECT_EQ(rejected, 0);
	EXPECT_EQ(ra.inliers, rp.inliers);
	EXPECT_NEAR(poseError(anchored, plain), 0.0, 1e-4);  // the same optimum (solver paths differ)
	// Too few anchors (100 < 150): exactly the plain refinement.
	CPose3D few = start;
	const auto rf = optimizePoseAnchored(few, s.obs, isAnchor, K, {}, 9.0, 150, &rejected);
	EXPECT_EQ(rejected, 0);
	EXPECT_EQ(rf.inlier, rp.inlier);
	EXPECT_NEAR(poseError(few, plain), 0.0, 1e-12);
	EXPECT_THROW(optimizePoseAnchored(few, s.obs, std::vector<char>(3, 1), K, {}, 9.0, 30), std::invalid_argument);
}

TEST(PoseOptimizer, ObservationChi2MatchesTheHandComputedResidual)
{
	const auto s = makeScene(1, 0.0, 0, 5);
	auto ob = s.obs[0];
	PoseOptimizerOptions o;
	EXPECT_NEAR(observationChi2(s.T_world_cam, ob, K, o), 0.0, 1e-12);
	ob.uv += Eigen::Vector2d(3.0, -4.0);  // 5 px off
	ob.invSigma = 0.5;                    // level sigma 2 px: (5 / 2)^2
	EXPECT_NEAR(observationChi2(s.T_world_cam, ob, K, o), 6.25, 1e-9);
	EXPECT_DOUBLE_EQ(inlierThreshold(ob, o), o.chi2Rgbd);
	// Depth 2 % too far: disparity error bf / d (1 - 1 / 1.02), divided by disparity_sigma.
	ob.uv = s.obs[0].uv;
	ob.depth = s.obs[0].depth * 1.02;
	const double dr = (o.bf / s.obs[0].depth - o.bf / ob.depth) / o.disparitySigma;
	EXPECT_NEAR(observationChi2(s.T_world_cam, ob, K, o), dr * dr, 1e-9);
	ob.depth = 0;
	EXPECT_DOUBLE_EQ(inlierThreshold(ob, o), o.chi2Mono);
	// Behind the camera
	ob.p_world = Eigen::Vector3d(s.T_world_cam.x(), s.T_world_cam.y(), s.T_world_cam.z()) * 2.0 - s.obs[0].p_world;
	EXPECT_TRUE(std::isinf(observationChi2(s.T_world_cam, ob, K, o)));
}

TEST(PnpSolver, RecoversKnownPoseDespiteOutliers)
{
	const auto s = makeScene(150, 0.3, 40, 3);
	std::vector<Eigen::Vector3d> pw;
	std::vector<Eigen::Vector2d> px;
	for (const auto& o : s.obs)
	{
		pw.push_back(o.p_world);
		px.push_back(o.uv);
	}
	const auto r = solvePnpRansac(pw, px, K);
	ASSERT_TRUE(r.ok);
	EXPECT_GE(static_cast<int>(r.inliers.size()), 100);
	for (int i : r.inliers) EXPECT_GE(i, 40) << "an outlier was accepted";
	EXPECT_LT((r.T_world_cam - s.T_world_cam).translation().norm(), 0.01);
	// Same seed -> same result.
	const auto r2 = solvePnpRansac(pw, px, K);
	EXPECT_EQ(r.inliers, r2.inliers);
}

TEST(RgbdReprojectionCost, AutoDiffJacobianMatchesFiniteDifferences)
{
	RgbdReprojectionCost cost({300.0, 200.0}, 1.7, 40.0, 1.0 / 1.2, 4.0, K);
	auto* ad = new ceres::AutoDiffCostFunction<RgbdReprojectionCost, 3, 4, 3, 3>(new RgbdReprojectionCost(cost));
	auto* nd = new ceres::NumericDiffCostFunction<RgbdReprojectionCost, ceres::CENTRAL, 3, 4, 3, 3>(new RgbdReprojectionCost(cost));
	Eigen::Quaterniond q(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
	double qv[4] = {q.x(), q.y(), q.z(), q.w()}, t[3] = {0.1, -0.2, 0.5}, p[3] = {0.3, 0.2, 1.5};
	const double* params[3] = {qv, t, p};
	double ra[3], rn[3], ja[3][12], jn[3][12];
	double* Ja[3] = {ja[0], ja[1], ja[2]};
	double* Jn[3] = {jn[0], jn[1], jn[2]};
	ASSERT_TRUE(ad->Evaluate(params, ra, Ja));
	ASSERT_TRUE(nd->Evaluate(params, rn, Jn));
	const int sizes[3] = {4, 3, 3};
	for (int b = 0; b < 3; b++)
		for (int k = 0; k < 3 * sizes[b]; k++) EXPECT_NEAR(ja[b][k], jn[b][k], 1e-5 * (1 + std::abs(ja[b][k]))) << b << "," << k;
	// The third residual is the virtual-stereo (inverse depth) term: zero at the true depth.
	Eigen::Vector3d pc = q * Eigen::Vector3d(p[0], p[1], p[2]) + Eigen::Vector3d(t[0], t[1], t[2]);
	const double u = K.fx * pc.x() / pc.z() + K.cx, v = K.fy * pc.y() / pc.z() + K.cy;
	RgbdReprojectionCost exact({u, v}, pc.z(), 40.0, 1.0, 4.0, K);
	double r0[3] = {1, 1, 1};
	exact(qv, t, p, r0);
	EXPECT_NEAR(std::abs(r0[0]) + std::abs(r0[1]) + std::abs(r0[2]), 0.0, 1e-9);
	// A depth error alone moves only the third residual, to (bf / d - bf / z) / sigma_disparity,
	// whatever the keypoint's pyramid level (invSigma) is.
	for (const double invSigma : {1.0, 1.0 / std::pow(1.2, 5)})
	{
		const double d = pc.z() + 0.05;
		RgbdReprojectionCost deep({u, v}, d, 40.0, invSigma, 4.0, K);
		double r1[3];
		deep(qv, t, p, r1);
		EXPECT_NEAR(r1[0], 0.0, 1e-9);
		EXPECT_NEAR(r1[1], 0.0, 1e-9);
		EXPECT_NEAR(r1[2], (40.0 / d - 40.0 / pc.z()) * 4.0, 1e-9);
	}
	delete ad;
	delete nd;
}

TEST(Triangulation, DltRecoversAPointFromTwoViews)
{
	const CPose3D T1(0, 0, 0, 0, 0, 0), T2(0.3, 0.05, -0.02, 0.1, -0.05, 0.02);
	const Eigen::Vector3d p(0.4, -0.3, 2.5);
	auto project = [&](const CPose3D& T) {
		double x, y, z;
		(-T).composePoint(p.x(), p.y(), p.z(), x, y, z);
		return Eigen::Vector2d(K.fx * x / z + K.cx, K.fy * y / z + K.cy);
	};
	Eigen::Vector3d est;
	ASSERT_TRUE(triangulateDlt(T1, project(T1), T2, project(T2), K, est));
	EXPECT_NEAR((est - p).norm(), 0.0, 1e-9);
	EXPECT_NEAR(parallaxAngle(T1, T2, p), std::acos((p.normalized()).dot((p - Eigen::Vector3d(0.3, 0.05, -0.02)).normalized())), 1e-12);
	// Diverging rays (the right camera looks further right) meet behind both cameras: rejected.
	const CPose3D Tright(0.3, 0, 0, 0, 0, 0);
	EXPECT_FALSE(triangulateDlt(T1, Eigen::Vector2d(K.cx + 50, K.cy), Tright, Eigen::Vector2d(K.cx + 100, K.cy), K, est));
}
}  // namespace pose_optimizer_unittest
