#include <keygrid/eval/TrajectoryErrors.h>

#include <random>

#include "TestData.h"

using namespace keygrid;
using mrpt::poses::CPose3D;

namespace
{
// A wavy 3D trajectory at 30 Hz, camera turning as it goes.
core::Trajectory makeGroundTruth(int n, double rateHz = 30.0)
{
	core::Trajectory gt;
	for (int i = 0; i < n; i++)
	{
		const double t = 100.0 + i / rateHz;
		gt.push_back({t, CPose3D(std::cos(0.3 * t), std::sin(0.2 * t), 0.3 * std::sin(0.5 * t), 0.4 * t, 0.1 * std::sin(t), 0.05 * t)});
	}
	return gt;
}
}  // namespace

TEST(TrajectoryErrors, IdenticalTrajectoriesHaveZeroError)
{
	const auto gt = makeGroundTruth(300);
	const auto r = eval::evaluateTrajectory(gt, gt);
	EXPECT_EQ(r.matched, 300u);
	EXPECT_NEAR(r.ate.rmse, 0.0, 1e-12);
	ASSERT_TRUE(r.rpeTrans.has_value());
	EXPECT_NEAR(r.rpeTrans->rmse, 0.0, 1e-12);
	EXPECT_NEAR(r.rpeRotDeg->rmse, 0.0, 1e-5);  // acos near 1
}

TEST(TrajectoryErrors, RigidlyMovedTrajectoryAlignsExactlyAndNoiseRmseIsRecovered)
{
	const auto gt = makeGroundTruth(2000);
	const CPose3D T(3.0, -1.0, 0.5, 1.2, -0.4, 0.3);  // arbitrary rigid change of world frame
	std::mt19937 g(42);
	std::normal_distribution<double> nd(0, 0.01 / std::sqrt(3.0));  // 1 cm RMS 3D noise
	core::Trajectory moved, noisy;
	double sq = 0;
	for (const auto& p : gt)
	{
		moved.push_back({p.t, T + p.T_world_cam});
		const mrpt::math::TPoint3D e(nd(g), nd(g), nd(g));
		sq += e.sqrNorm();
		CPose3D q = p.T_world_cam;
		q.x_incr(e.x);
		q.y_incr(e.y);
		q.z_incr(e.z);
		noisy.push_back({p.t, T + q});
	}
	const double noiseRmse = std::sqrt(sq / gt.size());
	const auto r0 = eval::evaluateTrajectory(gt, moved);
	EXPECT_NEAR(r0.ate.rmse, 0.0, 1e-9);
	EXPECT_NEAR(r0.rpeTrans->rmse, 0.0, 1e-9);
	const auto r1 = eval::evaluateTrajectory(gt, noisy);
	EXPECT_NEAR(r1.ate.rmse, noiseRmse, 1e-4) << "noise rmse " << noiseRmse;
}

TEST(TrajectoryErrors, RpeMatchesClosedFormDrift)
{
	// Ground truth: straight line at v = 0.5 m/s along x, no rotation.
	// Estimate: 2 % too fast and yawing at 3 deg/s about the camera axis.
	core::Trajectory gt, est;
	const double v = 0.5, w = mrpt::DEG2RAD(3.0);
	for (int i = 0; i < 301; i++)
	{
		const double t = i / 30.0;
		gt.push_back({t, CPose3D(v * t, 0, 0, 0, 0, 0)});
		est.push_back({t, CPose3D(1.02 * v * t, 0, 0, w * t, 0, 0)});
	}
	const auto r = eval::evaluateTrajectory(gt, est);
	ASSERT_TRUE(r.rpeRotDeg.has_value());
	EXPECT_NEAR(r.rpeRotDeg->rmse, 3.0, 1e-9);
	EXPECT_NEAR(r.rpeRotDeg->max, 3.0, 1e-9);
	// Over 1 s: relEst = (yaw rotation, translation rotated by the yaw so far) — E's translation
	// is |R(-w*t_i)... | of length |1.02 v| - v in the limit of no rotation; with rotation the
	// estimate's displacement over 1 s, expressed in its frame at t_i, is 1.02 v along a chord.
	// Closed form: displacement in body frame at t_i = R(-w t_i) * 1.02 v [1,0,0]; gt rel = v [1,0,0];
	// E.t = relEst.t - relGt.t (relGt is a pure translation) -> |E.t| varies with t_i.
	std::vector<double> expected;
	for (int i = 0; i + 30 <= 300; i++)
	{
		const double ti = i / 30.0;
		const double ex = 1.02 * v * std::cos(-w * ti) - v, ey = 1.02 * v * std::sin(-w * ti);
		expected.push_back(std::sqrt(ex * ex + ey * ey));
	}
	const auto es = eval::ErrorStats::Of(expected);
	EXPECT_EQ(r.rpeTrans->count, expected.size());
	EXPECT_NEAR(r.rpeTrans->rmse, es.rmse, 1e-9);
}

TEST(TrajectoryErrors, TimestampToleranceAndShortSequences)
{
	const auto gt = makeGroundTruth(60, 10.0);  // 100 ms apart: a 30 ms lag has no neighbour
	core::Trajectory late5 = gt, late30 = gt;
	for (auto& p : late5) p.t += 0.005;
	for (auto& p : late30) p.t += 0.030;
	EXPECT_EQ(eval::evaluateTrajectory(gt, late5).matched, 60u);
	EXPECT_THROW(eval::evaluateTrajectory(gt, late30), std::invalid_argument);
	eval::TrajectoryErrorOptions o;
	o.maxDt = 0.05;
	EXPECT_EQ(eval::evaluateTrajectory(gt, late30, o).matched, 60u);

	const auto gt30 = makeGroundTruth(9);
	const core::Trajectory shortGt(gt30.begin(), gt30.end());  // 0.27 s < RPE delta
	const auto r = eval::evaluateTrajectory(shortGt, shortGt);
	EXPECT_FALSE(r.rpeTrans.has_value());
	const std::string js = r.toJson();
	EXPECT_NE(js.find("\"rpe_trans_m_per_s\": null"), std::string::npos) << js;
	EXPECT_NE(js.find("\"matched\": 9"), std::string::npos) << js;
	EXPECT_LT(r.ate.rmse, 1e-12);
	EXPECT_NE(js.find("\"ate_rmse_m\": "), std::string::npos) << js;
	o.rpeDelta = -1;
	EXPECT_THROW(eval::evaluateTrajectory(gt, gt, o), std::invalid_argument);
}

TEST(TrajectoryErrors, OrientationErrorIsTheKnownPerturbationAngleAlsoForAStaticCamera)
{
	// est_k = W * gt_k * N_k with W an arbitrary change of world frame and N_k a rotation of
	// 0.5 deg about the camera's x axis, alternating in sign: sum_k R_gt N_k^T R_gt^T R_W^T is
	// a symmetric positive matrix times R_W^T, so the chordal alignment recovers W exactly and
	// every residual angle is 0.5 deg (static camera: exactly; moving camera: consecutive
	// perturbations cancel only up to the camera's rotation between frames, ~0.002 deg).
	const CPose3D W(3.0, -1.0, 0.5, 1.2, -0.4, 0.3);
	const double angle = mrpt::DEG2RAD(0.5);
	for (bool still : {false, true})
	{
		core::Trajectory gt, est;
		for (int i = 0; i < 300; i++)
		{
			const double t = 10 + i / 30.0;
			const CPose3D g = still ? CPose3D(1, 2, 3, 0.3, 0.2, 0.1) : CPose3D(std::cos(t), std::sin(t), 0.1 * t, 0.4 * t, 0.1 * std::sin(t), 0.05 * t);
			gt.push_back({t, g});
			est.push_back({t, W + g + CPose3D(0, 0, 0, 0, 0, (i % 2 ? 1 : -1) * angle)});
		}
		const auto r = eval::evaluateTrajectory(gt, est);
		const double tol = still ? 1e-6 : 3e-3;
		EXPECT_NEAR(r.ateRotDeg.rmse, 0.5, tol) << (still ? "static camera" : "moving camera");
		EXPECT_NEAR(r.ateRotDeg.max, 0.5, tol);
	}
}

TEST(TrajectoryErrors, AFixedAlignmentMeasuresInTheGivenFrameWithoutRefitting)
{
	// Two runs in one world: the first run's alignment (here exact) puts the second run's
	// estimate into the ground-truth frame. An estimate offset by 3 cm along x in that frame
	// has ATE 3 cm with the fixed alignment; a fitted one would absorb the offset.
	const auto gt = makeGroundTruth(300);
	const CPose3D T_est_world(0.5, 0.2, -0.1, 0.3, 0.1, -0.2);
	core::Trajectory est;
	for (const auto& p : gt)
	{
		CPose3D shifted = p.T_world_cam;
		shifted.x_incr(0.03);
		est.push_back({p.t, T_est_world + shifted});
	}
	eval::TrajectoryErrorOptions o;
	CPose3D T_world_est = T_est_world;
	T_world_est.inverse();
	eval::Similarity3 a;
	a.R = T_world_est.getRotationMatrix().asEigen();
	a.t = Eigen::Vector3d(T_world_est.x(), T_world_est.y(), T_world_est.z());
	o.fixedAlignment = a;
	const auto fixed = eval::evaluateTrajectory(gt, est, o);
	EXPECT_NEAR(fixed.ate.rmse, 0.03, 1e-9);
	EXPECT_NEAR(fixed.ateRotDeg.rmse, 0.0, 1e-5);
	EXPECT_NEAR(eval::evaluateTrajectory(gt, est).ate.rmse, 0.0, 1e-9);
}
