/** The similarity between two monocular keyframes from their matched map points (Sim3Ransac.h):
 * reprojection errors in closed form, exact recovery without noise, and recovery with pixel and
 * depth noise and 40 % wrong matches within bounds derived from the noise. */
#include <gtest/gtest.h>
#include <keygrid/loop/Sim3Ransac.h>

#include <cmath>
#include <random>

using namespace keygrid::loop;
using keygrid::core::PinholeIntrinsics;

namespace
{
/** The truth of a scene seen by keyframes a and b: a's map units are metres, b's are
 * `unitsB` map units per metre (its part of the map drifted in scale). */
struct Scene
{
	Eigen::Isometry3d T_a_b{Eigen::Isometry3d::Identity()};  //!< metric
	double unitsB{0.6};
	/** S_a_b: b's map coordinates -> a's: p_a = T_a_b (p_b / unitsB) */
	Sim3 S_a_b() const { return Sim3{Eigen::Quaterniond(T_a_b.linear()), T_a_b.translation(), 1.0 / unitsB}; }
};

Scene makeScene()
{
	Scene s;
	s.T_a_b.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d(0.1, 1.0, 0.2).normalized()).toRotationMatrix();
	s.T_a_b.translation() = Eigen::Vector3d(0.5, -0.1, 0.2);
	return s;
}

Eigen::Vector2d project(const PinholeIntrinsics& K, const Eigen::Vector3d& p) { return {K.fx * p.x() / p.z() + K.cx, K.fy * p.y() / p.z() + K.cy}; }

/** n matches of points 2-6 m in front of b; pixels with N(0, pixelSigma) noise, map points with
 * a relative depth error N(0, depthSigma) (monocular points are uncertain along their ray);
 * a share `wrong` of the matches pairs a's side with another point. isRight says which. */
std::vector<Sim3Match> makeMatches(
	const Scene& s, const PinholeIntrinsics& K, int n, double pixelSigma, double depthSigma, double wrong, std::vector<char>& isRight,
	std::uint64_t seed)
{
	std::mt19937_64 rng(seed);
	std::uniform_real_distribution<double> u(-0.6, 0.6), z(2.0, 6.0), coin(0.0, 1.0);
	std::normal_distribution<double> g(0.0, 1.0);
	std::vector<Eigen::Vector3d> pts_b;
	for (int i = 0; i < n; ++i)
	{
		const double d = z(rng);
		pts_b.emplace_back(u(rng) * d, 0.75 * u(rng) * d, d);
	}
	std::vector<Sim3Match> out;
	isRight.clear();
	for (int i = 0; i < n; ++i)
	{
		const bool right = coin(rng) >= wrong;
		const Eigen::Vector3d pb = pts_b[static_cast<std::size_t>(i)];
		const Eigen::Vector3d pa = s.T_a_b * pts_b[static_cast<std::size_t>(right ? i : (i + n / 2) % n)];
		Sim3Match m;
		m.p_b = s.unitsB * pb * (1 + depthSigma * g(rng));
		m.p_a = pa * (1 + depthSigma * g(rng));
		m.uv_b = project(K, pb) + pixelSigma * Eigen::Vector2d(g(rng), g(rng));
		m.uv_a = project(K, pa) + pixelSigma * Eigen::Vector2d(g(rng), g(rng));
		out.push_back(m);
		isRight.push_back(right);
	}
	return out;
}

double angleDeg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) { return a.angularDistance(b) * 180.0 / M_PI; }
}  // namespace

TEST(Sim3Ransac, ReprojectionErrorsInClosedForm)
{
	const PinholeIntrinsics K;  // fx = fy = 525, cx = 319.5, cy = 239.5
	// S_a_b = (2, I, (0.1, 0, 0)): p_b = (0, 0, 1) -> (0.1, 0, 2) in a, at u = 319.5 + 525 * 0.05.
	const Sim3 S{Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.1, 0, 0), 2.0};
	Sim3Match m;
	m.p_b = Eigen::Vector3d(0, 0, 1);
	m.uv_a = Eigen::Vector2d(319.5 + 26.25 + 3.0, 239.5);  // 3 px off
	// p_a = (0.1, 0, 2) maps back to ((0.1 - 0.1) / 2, 0, 1) in b: the principal point.
	m.p_a = Eigen::Vector3d(0.1, 0, 2);
	m.uv_b = Eigen::Vector2d(319.5, 239.5 - 4.0);  // 4 px off
	const Eigen::Vector2d e2 = sim3ReprojectionErrors(m, S, K);
	EXPECT_NEAR(e2[0], 9.0, 1e-9);
	EXPECT_NEAR(e2[1], 16.0, 1e-9);
	// Behind camera a: infinite.
	m.p_b = Eigen::Vector3d(0, 0, -1);
	EXPECT_TRUE(std::isinf(sim3ReprojectionErrors(m, S, K)[0]));
}

TEST(Sim3Ransac, RecoversTheSimilarityExactlyWithoutNoise)
{
	const PinholeIntrinsics K;
	const Scene s = makeScene();
	std::vector<char> isRight;
	const auto ms = makeMatches(s, K, 60, 0.0, 0.0, 0.0, isRight, 3);
	const auto r = estimateSim3Ransac(ms, K);
	ASSERT_TRUE(r.success);
	EXPECT_EQ(r.numInliers, 60);
	EXPECT_NEAR(r.S_a_b.s, 1.0 / s.unitsB, 1e-9);
	EXPECT_LT(angleDeg(r.S_a_b.q, s.S_a_b().q), 1e-6);
	EXPECT_LT((r.S_a_b.t - s.T_a_b.translation()).norm(), 1e-9);
}

TEST(Sim3Ransac, RecoversTheSimilarityWithNoiseAndFortyPercentWrongMatches)
{
	const PinholeIntrinsics K;
	const Scene s = makeScene();
	for (std::uint64_t seed : {1u, 2u, 3u, 4u, 5u})
	{
		SCOPED_TRACE("seed " + std::to_string(seed));
		std::vector<char> isRight;
		constexpr double pixelSigma = 0.7, depthSigma = 0.005;
		const auto ms = makeMatches(s, K, 150, pixelSigma, depthSigma, 0.4, isRight, seed);
		const auto r = estimateSim3Ransac(ms, K);
		ASSERT_TRUE(r.success);
		int right = 0, rightFound = 0, wrongTaken = 0;
		for (std::size_t i = 0; i < ms.size(); ++i)
		{
			right += isRight[i];
			rightFound += isRight[i] && r.inlier[i];
			wrongTaken += !isRight[i] && r.inlier[i];
		}
		// A right match's reprojection error in the other image: the pixel noise of both
		// keypoints (0.7 px each) and the depth error seen across the 0.56 m baseline, at most
		// 525 px x 0.56 m x 0.5 % / 2 m = 0.7 px: about 1.2 px per axis. The 3 px test
		// (chi-square 9.21 at sigma 1) loses a few percent of them in each image; a wrong match
		// lands within 3 px of its keypoint in both images by chance rarely.
		EXPECT_GE(rightFound, static_cast<int>(0.9 * right));
		EXPECT_LE(wrongTaken, 2);
		// Scale: each map point's depth is 0.5 % off, on both sides; over ~90 pairs the scale
		// is good to about 0.7 % / sqrt(90) = 0.07 %; bound 1 % (the refinement weighs points
		// by their reprojections, not evenly).
		EXPECT_NEAR(r.S_a_b.s * s.unitsB, 1.0, 0.01);
		// Rotation: 1.2 px / 525 px over ~90 points = 0.014 deg; bound 0.1 deg.
		EXPECT_LT(angleDeg(r.S_a_b.q, s.S_a_b().q), 0.1);
		// Translation: bound 2 cm, the rotation bound over the points' mean depth of 4 m plus
		// the scale bound over the 0.56 m baseline.
		EXPECT_LT((r.S_a_b.t - s.T_a_b.translation()).norm(), 0.02);
	}
}

// A monocular map made metric (fixScale): both sides in metres, the fit is rigid. The scale
// stays exactly 1 while rotation and translation meet the free fit's bounds; without noise the
// motion is exact.
TEST(Sim3Ransac, WithAFixedScaleFitsTheRigidMotionOfAMetricMap)
{
	const PinholeIntrinsics K;
	Scene s = makeScene();
	s.unitsB = 1.0;
	Sim3RansacOptions o;
	o.fixScale = true;
	std::vector<char> isRight;
	const auto exact = estimateSim3Ransac(makeMatches(s, K, 60, 0.0, 0.0, 0.0, isRight, 3), K, o);
	ASSERT_TRUE(exact.success);
	EXPECT_EQ(exact.numInliers, 60);
	EXPECT_EQ(exact.S_a_b.s, 1.0);
	EXPECT_LT(angleDeg(exact.S_a_b.q, s.S_a_b().q), 1e-6);
	EXPECT_LT((exact.S_a_b.t - s.T_a_b.translation()).norm(), 1e-9);
	for (std::uint64_t seed : {1u, 2u, 3u})
	{
		SCOPED_TRACE("seed " + std::to_string(seed));
		const auto ms = makeMatches(s, K, 150, 0.7, 0.005, 0.4, isRight, seed);
		const auto r = estimateSim3Ransac(ms, K, o);
		ASSERT_TRUE(r.success);
		EXPECT_EQ(r.S_a_b.s, 1.0);
		int right = 0, rightFound = 0;
		for (std::size_t i = 0; i < ms.size(); ++i)
		{
			right += isRight[i];
			rightFound += isRight[i] && r.inlier[i];
		}
		EXPECT_GE(rightFound, static_cast<int>(0.9 * right));
		EXPECT_LT(angleDeg(r.S_a_b.q, s.S_a_b().q), 0.1);
		EXPECT_LT((r.S_a_b.t - s.T_a_b.translation()).norm(), 0.02);
	}
}

TEST(Sim3Ransac, FailsWithTooFewMatchesAndRejectsBadOptions)
{
	const PinholeIntrinsics K;
	std::vector<char> isRight;
	const auto ms = makeMatches(makeScene(), K, 15, 0.0, 0.0, 0.0, isRight, 1);
	// 15 consistent matches are fewer than the 20 inliers needed.
	const auto r = estimateSim3Ransac(ms, K);
	EXPECT_FALSE(r.success);
	EXPECT_EQ(r.numInliers, 15);
	EXPECT_FALSE(estimateSim3Ransac({ms.begin(), ms.begin() + 2}, K).success);
	Sim3RansacOptions bad;
	bad.inlierChi2 = 0;
	EXPECT_THROW(estimateSim3Ransac(ms, K, bad), std::invalid_argument);
	bad = {};
	bad.confidence = 1.0;
	EXPECT_THROW(bad.validate(), std::invalid_argument);
}
