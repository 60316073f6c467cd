// Rolling-shutter compensation against closed forms: a camera moving with constant rates sees
// each row at its own time; compensated keypoints must be the global-shutter projections.
#include <keygrid/sfm/RollingShutter.h>

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

using namespace keygrid;

namespace
{
const sfm::PinholeIntrinsics kK{520.0, 515.0, 318.0, 244.0};
constexpr double kHeight = 480;

Eigen::Vector2d project(const Eigen::Vector3d& p) { return {kK.fx * p.x() / p.z() + kK.cx, kK.fy * p.y() / p.z() + kK.cy}; }

/** The camera at t + tau relative to the camera at t: (exp(tau [w]x), tau v), the model. */
Eigen::Isometry3d motion(const sfm::CameraRates& r, double tau)
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	const Eigen::Vector3d rot = tau * r.omega;
	if (rot.norm() > 0) T.linear() = Eigen::AngleAxisd(rot.norm(), rot.normalized()).toRotationMatrix();
	T.translation() = tau * r.velocity;
	return T;
}

struct Scene
{
	std::vector<Eigen::Vector3d> points_t;  // in the camera at the frame time t
	sfm::FrameFeatures features;            // as a rolling-shutter camera measures them
};

/** Points 1-4 m ahead; each measured at the row where the moving camera sees it (the
 * row time depends on the row: fixed-point iteration converges in a few steps). */
Scene rollingShutterScene(const sfm::CameraRates& rates, double readout, bool withDepth)
{
	Scene s;
	s.features.camera.width = 640;
	s.features.camera.height = static_cast<unsigned>(kHeight);
	std::mt19937 g(3);
	std::uniform_real_distribution<double> U(0, 1);
	while (s.points_t.size() < 300)
	{
		const double z = 1.0 + 3.0 * U(g);
		const Eigen::Vector3d p((U(g) - 0.5) * 1.1 * z, (U(g) - 0.5) * 0.8 * z, z);
		double y = project(p).y();
		Eigen::Vector3d seen = p;
		for (int it = 0; it < 30; it++)
		{
			const double tau = sfm::rowTimeOffset(y, kHeight, readout);
			seen = motion(rates, tau).inverse() * p;  // the point in the camera at t + tau
			y = project(seen).y();
		}
		const Eigen::Vector2d uv = project(seen);
		if (uv.x() < 0 || uv.x() >= 640 || uv.y() < 0 || uv.y() >= kHeight) continue;
		s.points_t.push_back(p);
		cv::KeyPoint kp(static_cast<float>(uv.x()), static_cast<float>(uv.y()), 31.f);
		s.features.keypoints.push_back(kp);
		s.features.undistorted.emplace_back(kp.pt);  // no lens distortion here
		s.features.depth.push_back(withDepth ? static_cast<float>(seen.z()) : 0.f);
	}
	s.features.buildGrid();
	return s;
}

/** Every keypoint at the global-shutter projection of its point (within 2e-3 px). */
void expectGlobalShutterPositions(const Scene& s)
{
	for (std::size_t i = 0; i < s.points_t.size(); i++)
	{
		const Eigen::Vector2d gs = project(s.points_t[i]);
		EXPECT_NEAR(s.features.undistorted[i].x, gs.x(), 2e-3) << i;
		EXPECT_NEAR(s.features.undistorted[i].y, gs.y(), 2e-3) << i;
	}
}

sfm::CameraRates fastRates()
{
	sfm::CameraRates r;
	r.omega = Eigen::Vector3d(0.4, -1.2, 0.3);  // ~75 deg/s, mostly a pan
	r.velocity = Eigen::Vector3d(0.25, -0.05, 0.1);
	return r;
}
}  // namespace

TEST(RollingShutter, RatesFromRelativePoseAreTheClosedForm)
{
	const Eigen::Vector3d axis = Eigen::Vector3d(1, -2, 0.5).normalized();
	const double angle = 0.07, dt = 1.0 / 30;
	const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
	mrpt::math::CMatrixDouble33 Rm;
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++) Rm(i, j) = R(i, j);
	mrpt::math::CVectorFixedDouble<3> t;
	t[0] = 0.01;
	t[1] = -0.004;
	t[2] = 0.002;
	const auto rates = sfm::ratesFromRelativePose(mrpt::poses::CPose3D::FromRotationAndTranslation(Rm, t), dt);
	EXPECT_NEAR((rates.omega - axis * angle / dt).norm(), 0.0, 1e-9);
	EXPECT_NEAR((rates.velocity - Eigen::Vector3d(0.3, -0.12, 0.06)).norm(), 0.0, 1e-9);
	EXPECT_THROW(sfm::ratesFromRelativePose(mrpt::poses::CPose3D(), 0.0), std::invalid_argument);
}

TEST(RollingShutter, RowTimeIsZeroAtTheMiddleRow)
{
	EXPECT_DOUBLE_EQ(sfm::rowTimeOffset(240, 480, 0.03), 0.0);
	EXPECT_DOUBLE_EQ(sfm::rowTimeOffset(0, 480, 0.03), -0.015);
	EXPECT_DOUBLE_EQ(sfm::rowTimeOffset(480, 480, 0.03), 0.015);
}

TEST(RollingShutter, CompensatedKeypointsWithDepthAreTheGlobalShutterProjections)
{
	const auto rates = fastRates();
	auto s = rollingShutterScene(rates, 0.03, true);
	// Uncompensated, the measurements are several pixels off the global-shutter view.
	double before = 0;
	for (std::size_t i = 0; i < s.points_t.size(); i++)
		before = std::max(before, (project(s.points_t[i]) - Eigen::Vector2d(s.features.undistorted[i].x, s.features.undistorted[i].y)).norm());
	EXPECT_GT(before, 5.0);

	const sfm::RollingShutterCompensator rs(s.features, 0.03);
	rs.apply(s.features, rates, kK);
	expectGlobalShutterPositions(s);
	for (std::size_t i = 0; i < s.points_t.size(); i++) EXPECT_NEAR(s.features.depth[i], s.points_t[i].z(), 1e-5) << i;
	// The area grid follows the new positions.
	const auto& u = s.features.undistorted[7];
	const auto near = s.features.featuresInArea(u.x, u.y, 0.5f);
	EXPECT_NE(std::find(near.begin(), near.end(), 7), near.end());
}

TEST(RollingShutter, WithoutDepthOnlyTheRotationIsCompensated)
{
	// Pure rotation: bearings alone carry the whole effect, so compensation is exact.
	sfm::CameraRates rates;
	rates.omega = Eigen::Vector3d(-0.9, 0.8, 0.2);
	auto s = rollingShutterScene(rates, 0.025, false);
	const sfm::RollingShutterCompensator rs(s.features, 0.025);
	rs.apply(s.features, rates, kK);
	expectGlobalShutterPositions(s);
	for (float d : s.features.depth) EXPECT_EQ(d, 0.f);
}

TEST(RollingShutter, ApplyStartsFromTheMeasurementsEachTime)
{
	const auto rates = fastRates();
	auto s = rollingShutterScene(rates, 0.03, true);
	const auto measured = s.features.undistorted;
	const auto measuredDepth = s.features.depth;
	const sfm::RollingShutterCompensator rs(s.features, 0.03);
	sfm::CameraRates wrong;
	wrong.omega = Eigen::Vector3d(2, 0, 0);
	rs.apply(s.features, wrong, kK);
	rs.apply(s.features, rates, kK);  // not on top of the first call
	expectGlobalShutterPositions(s);
	rs.apply(s.features, sfm::CameraRates{}, kK);  // zero rates: the measurements, bit for bit
	for (std::size_t i = 0; i < measured.size(); i++)
	{
		EXPECT_EQ(s.features.undistorted[i], measured[i]);
		EXPECT_EQ(s.features.depth[i], measuredDepth[i]);
	}
}

TEST(RollingShutter, RejectsBadInput)
{
	sfm::FrameFeatures f;
	EXPECT_THROW(sfm::RollingShutterCompensator(f, -0.01), std::invalid_argument);
	const sfm::RollingShutterCompensator rs(f, 0.02);
	sfm::FrameFeatures other;
	other.keypoints.resize(3);
	other.undistorted.resize(3);
	other.depth.resize(3);
	EXPECT_THROW(rs.apply(other, fastRates(), kK), std::invalid_argument);
}
