#include <keygrid/eval/Alignment.h>

#include <Eigen/Geometry>
#include <random>

#include "TestData.h"

using keygrid::eval::alignPointSets;

namespace
{
std::vector<Eigen::Vector3d> randomPoints(int n, unsigned seed)
{
	std::mt19937 g(seed);
	std::uniform_real_distribution<double> u(-3, 3);
	std::vector<Eigen::Vector3d> p;
	for (int i = 0; i < n; i++) p.emplace_back(u(g), u(g), u(g));
	return p;
}
}  // namespace

TEST(Alignment, RecoversKnownRigidAndSimilarityTransforms)
{
	const auto x = randomPoints(50, 3);
	const Eigen::Matrix3d R =
		Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
	const Eigen::Vector3d t(0.4, -1.2, 2.5);
	for (double s : {1.0, 1.7})
	{
		std::vector<Eigen::Vector3d> y;
		for (const auto& p : x) y.push_back(s * R * p + t);
		const auto a = alignPointSets(x, y, s != 1.0);
		EXPECT_NEAR((a.R - R).norm(), 0.0, 1e-12);
		EXPECT_NEAR((a.t - t).norm(), 0.0, 1e-12);
		EXPECT_NEAR(a.s, s, 1e-12);
	}
}

TEST(Alignment, AgreesWithEigenUmeyamaOnNoisyData)
{
	// An independent implementation (Eigen::umeyama) on noisy, imperfect correspondences.
	const auto x = randomPoints(200, 5);
	std::mt19937 g(9);
	std::normal_distribution<double> noise(0, 0.05);
	const Eigen::Matrix3d R = Eigen::AngleAxisd(-1.1, Eigen::Vector3d(0.2, 1, 0.3).normalized()).toRotationMatrix();
	Eigen::Matrix3Xd X(3, x.size()), Y(3, x.size());
	std::vector<Eigen::Vector3d> y;
	for (std::size_t i = 0; i < x.size(); i++)
	{
		y.push_back(0.8 * R * x[i] + Eigen::Vector3d(1, 2, 3) + Eigen::Vector3d(noise(g), noise(g), noise(g)));
		X.col(static_cast<Eigen::Index>(i)) = x[i];
		Y.col(static_cast<Eigen::Index>(i)) = y[i];
	}
	for (bool scale : {false, true})
	{
		const Eigen::Matrix4d ref = Eigen::umeyama(X, Y, scale);
		const auto a = alignPointSets(x, y, scale);
		Eigen::Matrix4d mine = Eigen::Matrix4d::Identity();
		mine.topLeftCorner<3, 3>() = a.s * a.R;
		mine.topRightCorner<3, 1>() = a.t;
		EXPECT_NEAR((mine - ref).norm(), 0.0, 1e-10) << "scale=" << scale;
	}
}

TEST(Alignment, NeverReturnsAReflection)
{
	// Points mirrored in a plane: the best proper rotation has det +1.
	auto x = randomPoints(30, 11);
	std::vector<Eigen::Vector3d> y;
	for (const auto& p : x) y.emplace_back(p.x(), p.y(), -p.z());
	const auto a = alignPointSets(x, y, false);
	EXPECT_NEAR(a.R.determinant(), 1.0, 1e-12);
}

TEST(Alignment, RejectsTooFewAndHandlesDegeneratePoints)
{
	std::vector<Eigen::Vector3d> two = {{0, 0, 0}, {1, 0, 0}};
	EXPECT_THROW(alignPointSets(two, two, false), std::invalid_argument);
	// Collinear: the residual is still exactly zero for a rigidly moved line.
	const Eigen::Matrix3d R = Eigen::AngleAxisd(0.9, Eigen::Vector3d(0, 1, 1).normalized()).toRotationMatrix();
	std::vector<Eigen::Vector3d> line = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}}, moved;
	for (const auto& p : line) moved.push_back(R * p + Eigen::Vector3d(1, 2, 3));
	const auto a = alignPointSets(line, moved, false);
	EXPECT_NEAR(a.R.determinant(), 1.0, 1e-12);
	for (std::size_t i = 0; i < line.size(); i++) EXPECT_NEAR((a.apply(line[i]) - moved[i]).norm(), 0.0, 1e-12);
	// Coincident: identity rotation, pure translation.
	std::vector<Eigen::Vector3d> same(3, Eigen::Vector3d(1, 1, 1)), other(3, Eigen::Vector3d(2, 0, 1));
	const auto b = alignPointSets(same, other, false);
	EXPECT_NEAR((b.R - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-15);
	EXPECT_NEAR((b.apply(same[0]) - other[0]).norm(), 0.0, 1e-15);
}

TEST(Alignment, PosesFixTheRotationWhereTheCameraOnlyTurns)
{
	// A camera turning on the spot: its positions all lie within 2 mm, measured with 1 mm
	// noise, so a position fit cannot see the rotation between the frames; the orientations
	// give it exactly.
	const mrpt::poses::CPose3D T_y_x(0.4, -1.2, 0.3, 0.7, -0.2, 0.1);
	std::mt19937 g(5);
	std::uniform_real_distribution<double> noise(-0.001, 0.001);
	std::vector<mrpt::poses::CPose3D> x, y;
	std::vector<Eigen::Vector3d> px, py;
	for (int k = 0; k < 40; k++)
	{
		const mrpt::poses::CPose3D p(0.001 * std::sin(k), 0.001 * std::cos(k), 0.0, 0.1 * k, 0.05 * std::sin(0.3 * k), 0.02 * k);
		x.push_back(p);
		y.push_back(T_y_x + p);
		y.back().x_incr(noise(g));
		y.back().y_incr(noise(g));
		y.back().z_incr(noise(g));
		px.emplace_back(x.back().x(), x.back().y(), x.back().z());
		py.emplace_back(y.back().x(), y.back().y(), y.back().z());
	}
	const auto a = keygrid::eval::alignPoses(x, y);
	const Eigen::Matrix3d R = T_y_x.getRotationMatrix().asEigen();
	EXPECT_LT((a.R - R).norm(), 1e-9);
	EXPECT_LT((a.t - Eigen::Vector3d(T_y_x.x(), T_y_x.y(), T_y_x.z())).norm(), 1e-3) << "the mean of the noise";
	EXPECT_DOUBLE_EQ(a.s, 1.0);
	// The position fit of the same data is far off (the reason for alignPoses).
	EXPECT_GT((alignPointSets(px, py, false).R - R).norm(), 0.03) << "over a degree";
	EXPECT_THROW(keygrid::eval::alignPoses({}, {}), std::invalid_argument);
}
