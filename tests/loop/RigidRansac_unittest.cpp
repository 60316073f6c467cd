#include <gtest/gtest.h>
#include <keygrid/loop/RigidRansac.h>

#include <cmath>
#include <random>

using namespace keygrid::loop;

namespace
{
struct Correspondences
{
	std::vector<Eigen::Vector3d> a, b;
	std::vector<char> isInlier;
};

/** n pairs, p_a = s R p_b + t + noise, a fraction of them replaced by random points. */
Correspondences makePairs(
	const Eigen::Isometry3d& T_a_b, double scale, int n, double outlierRatio, double noise, std::uint64_t seed)
{
	std::mt19937_64 rng(seed);
	std::uniform_real_distribution<double> u(-2.0, 2.0), depth(0.5, 4.0), coin(0.0, 1.0);
	std::normal_distribution<double> g(0.0, noise);
	Correspondences c;
	for (int i = 0; i < n; ++i)
	{
		const Eigen::Vector3d pb(u(rng), u(rng), depth(rng));
		Eigen::Vector3d pa = scale * (T_a_b.linear() * pb) + T_a_b.translation() + Eigen::Vector3d(g(rng), g(rng), g(rng));
		const bool outlier = coin(rng) < outlierRatio;
		if (outlier) pa = Eigen::Vector3d(u(rng), u(rng), depth(rng)) + T_a_b.translation();
		c.a.push_back(pa);
		c.b.push_back(pb);
		c.isInlier.push_back(!outlier);
	}
	return c;
}

Eigen::Isometry3d knownTransform()
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.linear() = (Eigen::AngleAxisd(0.6, Eigen::Vector3d(0.2, 1.0, -0.3).normalized())).toRotationMatrix();
	T.translation() = Eigen::Vector3d(0.8, -0.4, 1.5);
	return T;
}

double rotationErrorDeg(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B)
{
	return Eigen::AngleAxisd(A.transpose() * B).angle() * 180.0 / M_PI;
}
}  // namespace

TEST(RigidRansac, RecoversAKnownTransformWithFortyPercentOutliers)
{
	const Eigen::Isometry3d T = knownTransform();
	const auto c = makePairs(T, 1.0, 200, 0.4, 0.005, 1);
	const auto res = estimateRigidTransformRansac(c.a, c.b);
	ASSERT_TRUE(res.success);
	EXPECT_LT(rotationErrorDeg(res.T_a_b.linear(), T.linear()), 0.3);
	EXPECT_LT((res.T_a_b.translation() - T.translation()).norm(), 0.005);
	EXPECT_DOUBLE_EQ(res.scale, 1.0);
	// Classification against the truth: every true inlier found (noise 5 mm << 5 cm threshold),
	// random outliers almost never fall within 5 cm by chance.
	int missed = 0, falseInliers = 0, trueInliers = 0;
	for (std::size_t i = 0; i < c.a.size(); ++i)
	{
		trueInliers += c.isInlier[i];
		missed += c.isInlier[i] && !res.inlier[i];
		falseInliers += !c.isInlier[i] && res.inlier[i];
	}
	EXPECT_EQ(missed, 0);
	EXPECT_LE(falseInliers, 2);
	EXPECT_EQ(res.numInliers, trueInliers - missed + falseInliers);
	// RMS of 3D Gaussian noise with sigma 5 mm per axis: 5 mm * sqrt(3) = 8.7 mm.
	EXPECT_NEAR(res.rmse, 0.005 * std::sqrt(3.0), 0.002);

	// Same inputs and seed: same answer.
	const auto again = estimateRigidTransformRansac(c.a, c.b);
	EXPECT_TRUE(again.T_a_b.isApprox(res.T_a_b, 0.0));
	EXPECT_EQ(again.inlier, res.inlier);
}

TEST(RigidRansac, EstimatesScaleWhenAsked)
{
	const Eigen::Isometry3d T = knownTransform();
	const auto c = makePairs(T, 1.3, 150, 0.3, 0.002, 2);
	RigidRansacOptions o;
	o.estimateScale = true;
	const auto res = estimateRigidTransformRansac(c.a, c.b, o);
	ASSERT_TRUE(res.success);
	EXPECT_NEAR(res.scale, 1.3, 0.003);
	EXPECT_LT(rotationErrorDeg(res.T_a_b.linear(), T.linear()), 0.3);
	EXPECT_LT((res.T_a_b.translation() - T.translation()).norm(), 0.01);
}

TEST(RigidRansac, FailsOnPureOutliersAndTooFewPairs)
{
	const auto c = makePairs(knownTransform(), 1.0, 100, 1.0, 0.0, 3);
	const auto res = estimateRigidTransformRansac(c.a, c.b);
	EXPECT_FALSE(res.success);
	EXPECT_LT(res.numInliers, 20);
	EXPECT_FALSE(estimateRigidTransformRansac({Eigen::Vector3d::Zero()}, {Eigen::Vector3d::Zero()}).success);
	EXPECT_THROW(estimateRigidTransformRansac({Eigen::Vector3d::Zero()}, {}), std::invalid_argument);
	RigidRansacOptions bad;
	bad.inlierThreshold = -1;
	std::string why;
	EXPECT_FALSE(bad.isValid(&why));
	EXPECT_NE(why.find("inlier_threshold"), std::string::npos);
}
