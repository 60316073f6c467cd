// TwoViewInitializer (monocular map start) against synthetic correspondences with a
// known motion: points projected through a pinhole into a 640 x 480 image, Gaussian pixel noise
// of std sigma in both views and a share of outliers (current pixel drawn uniformly).
// Accuracy bounds come from the noise: the Cramer-Rao bound of the two-view problem (Fisher
// information of all reprojection residuals, points eliminated by the Schur complement)
// computed for each scene, times a stated factor; outlier bounds from the chance that a
// uniform pixel passes the chi-square gate.
#include <keygrid/sfm/TwoViewInitializer.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

using namespace keygrid::sfm;

namespace two_view_initializer_unittest
{
namespace
{
constexpr double kW = 640, kH = 480, kSigma = 1.0;
const PinholeIntrinsics kK{500.0, 500.0, 319.5, 239.5};
constexpr int kPoints = 300;
constexpr double kOutlierShare = 0.15;

Eigen::Vector2d project(const Eigen::Vector3d& X)
{
	return {kK.fx * X.x() / X.z() + kK.cx, kK.fy * X.y() / X.z() + kK.cy};
}

Eigen::Matrix3d cameraMatrix()
{
	Eigen::Matrix3d K;
	K << kK.fx, 0, kK.cx, 0, kK.fy, kK.cy, 0, 0, 1;
	return K;
}

bool inImage(const Eigen::Vector2d& p) { return p.x() >= 0 && p.x() < kW && p.y() >= 0 && p.y() < kH; }

Eigen::Matrix3d rotation(double rollDeg, double pitchDeg, double yawDeg)
{
	const double d = M_PI / 180.0;
	return (Eigen::AngleAxisd(yawDeg * d, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(pitchDeg * d, Eigen::Vector3d::UnitX()) *
			Eigen::AngleAxisd(rollDeg * d, Eigen::Vector3d::UnitZ()))
		.toRotationMatrix();
}

double angleDeg(const Eigen::Matrix3d& R) { return Eigen::AngleAxisd(R).angle() * 180.0 / M_PI; }

double angleBetweenDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
	return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

/** Ground truth and the correspondences made from it. */
struct Scene
{
	RelativeMotion truth;  //!< t with its true length
	std::vector<Eigen::Vector3d> X_ref;  //!< true point of each correspondence (outliers too)
	std::vector<uint8_t> outlier;
	TwoViewMatches matches;
	int numOutliers{0};
};

/** A plane n^T X = d in the reference frame, tilted 35 deg from the image plane, 4 m away. */
const Eigen::Vector3d kPlaneN = Eigen::Vector3d(0.6, -0.3, 1.0).normalized();
constexpr double kPlaneD = 4.0;

/** n correspondences: a uniform reference pixel with a depth uniform in [2, 6] m (general) or
 * the plane's intersection with its ray (planar), kept when in front of and inside both views;
 * then noise and, with probability outlierShare, a current pixel drawn uniformly instead. */
Scene makeScene(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, bool planar, int n, double outlierShare, uint32_t seed)
{
	Scene s;
	s.truth = {R, t};
	std::mt19937 rng(seed);
	std::uniform_real_distribution<double> u(0, kW), v(0, kH), depth(2.0, 6.0), unit(0, 1);
	std::normal_distribution<double> noise(0, kSigma);
	while (static_cast<int>(s.X_ref.size()) < n)
	{
		const Eigen::Vector3d ray((u(rng) - kK.cx) / kK.fx, (v(rng) - kK.cy) / kK.fy, 1.0);
		const Eigen::Vector3d X = planar ? Eigen::Vector3d(ray * kPlaneD / kPlaneN.dot(ray)) : Eigen::Vector3d(ray * depth(rng));
		const Eigen::Vector3d Xc = R * X + t;
		if (X.z() <= 0 || Xc.z() <= 0.5 || !inImage(project(Xc))) continue;
		const bool out = unit(rng) < outlierShare;
		const Eigen::Vector2d pr = project(X) + Eigen::Vector2d(noise(rng), noise(rng));
		const Eigen::Vector2d pc = out ? Eigen::Vector2d(u(rng), v(rng)) : Eigen::Vector2d(project(Xc) + Eigen::Vector2d(noise(rng), noise(rng)));
		s.X_ref.push_back(X);
		s.outlier.push_back(out ? 1 : 0);
		s.numOutliers += out ? 1 : 0;
		s.matches.px_ref.push_back(pr);
		s.matches.px_cur.push_back(pc);
	}
	return s;
}

/** The motions of the tests: a general scene 2-6 m deep seen with a 0.42 m baseline (median
 * parallax ~5 deg), the plane with a 1.2 m baseline (|t| / d = 0.3; at 0.2 the second
 * physical solution of the homography often keeps more than 75 % of the points in front of
 * both cameras, the two-fold ambiguity of a plane, and the initializer rightly refuses as
 * Ambiguous), and pure rotations. */
const Eigen::Matrix3d kR = rotation(2, -4, 6);
const Eigen::Vector3d kGeneralT(0.4, 0.05, 0.1), kPlanarT(1.2, 0.1, 0.1);

/** Cramer-Rao bound of the two-view problem on the scene's inliers: parameters rotation
 * (3, R = exp([w]) R_true), translation direction (2, on the sphere of radius |t|: the
 * scale gauge) and each point (3); residuals the 4 reprojection coordinates per point, std
 * sigma. Points are eliminated by the Schur complement of the Fisher information J^T J /
 * sigma^2; the 5 x 5 inverse is the covariance of an efficient estimator. Returns the rms
 * [deg] of the rotation error angle and of the translation direction error, and the rms error
 * of each point, sqrt(trace) of I_pp^-1 + I_pp^-1 I_pc C I_cp I_pp^-1 (C: the motion's
 * covariance). */
struct PoseBound
{
	double rotationDeg{0}, directionDeg{0};
	std::vector<double> pointRms;  //!< per correspondence (inliers), [m]
};

PoseBound cramerRao(const Scene& s)
{
	const Eigen::Vector3d t0 = s.truth.t_cur_ref;
	Eigen::Matrix<double, 3, 2> B;  // tangent basis of the translation sphere at t0
	B.col(0) = t0.unitOrthogonal();
	B.col(1) = t0.normalized().cross(B.col(0));
	// Residuals of the current view as a function of (w, a, X); the reference view depends on
	// X only. Central differences, step h.
	const auto cur = [&](const Eigen::Matrix<double, 5, 1>& c, const Eigen::Vector3d& X) {
		const Eigen::Matrix3d R = Eigen::AngleAxisd(c.head<3>().norm(), c.head<3>().norm() > 0 ? Eigen::Vector3d(c.head<3>().normalized()) : Eigen::Vector3d::UnitX()).toRotationMatrix() * s.truth.R_cur_ref;
		const Eigen::Vector3d t = (t0 + B * c.tail<2>()).normalized() * t0.norm();
		return project(R * X + t);
	};
	const double h = 1e-6;
	Eigen::Matrix<double, 5, 5> S = Eigen::Matrix<double, 5, 5>::Zero();
	std::vector<Eigen::Matrix<double, 4, 5>> Jcs(s.X_ref.size());
	std::vector<Eigen::Matrix<double, 4, 3>> Jps(s.X_ref.size());
	for (std::size_t i = 0; i < s.X_ref.size(); i++)
	{
		if (s.outlier[i]) continue;
		const Eigen::Vector3d& X = s.X_ref[i];
		auto& Jc = Jcs[i];
		auto& Jp = Jps[i];
		Jc.setZero();
		const Eigen::Matrix<double, 5, 1> c0 = Eigen::Matrix<double, 5, 1>::Zero();
		for (int k = 0; k < 5; k++)
		{
			Eigen::Matrix<double, 5, 1> dc = c0;
			dc(k) = h;
			Jc.block<2, 1>(2, k) = (cur(dc, X) - cur(-dc, X)) / (2 * h);
		}
		for (int k = 0; k < 3; k++)
		{
			Eigen::Vector3d dX = Eigen::Vector3d::Zero();
			dX(k) = h * X.norm();
			Jp.block<2, 1>(0, k) = (project(X + dX) - project(X - dX)) / (2 * dX(k));
			Jp.block<2, 1>(2, k) = (cur(c0, X + dX) - cur(c0, X - dX)) / (2 * dX(k));
		}
		S += Jc.transpose() * Jc - Jc.transpose() * Jp * (Jp.transpose() * Jp).inverse() * Jp.transpose() * Jc;
	}
	const Eigen::Matrix<double, 5, 5> cov = S.inverse() * kSigma * kSigma;
	PoseBound b;
	b.pointRms.assign(s.X_ref.size(), 0.0);
	for (std::size_t i = 0; i < s.X_ref.size(); i++)
	{
		if (s.outlier[i]) continue;
		const Eigen::Matrix3d IppInv = (Jps[i].transpose() * Jps[i]).inverse();
		const Eigen::Matrix<double, 3, 5> G = IppInv * Jps[i].transpose() * Jcs[i];  // dX / dmotion
		b.pointRms[i] = std::sqrt((IppInv * kSigma * kSigma + G * cov * G.transpose()).trace());
	}
	const double rad = 180.0 / M_PI;
	// The direction error angle of t0 + B a is |a| / |t0| to first order.
	b.rotationDeg = std::sqrt(cov.topLeftCorner<3, 3>().trace()) * rad;
	b.directionDeg = std::sqrt(cov.bottomRightCorner<2, 2>().trace()) / t0.norm() * rad;
	return b;
}

/** Statistics of a successful result against the truth. */
struct Errors
{
	double rotationDeg{0}, directionDeg{0};
	double medianPointError{0};  //!< median of |X_est |t_true| - X_true| / its Cramer-Rao rms, valid inliers
	int validInliers{0}, validOutliers{0}, inlierOutliers{0};
};

Errors compare(const Scene& s, const TwoViewResult& r, const PoseBound& crb)
{
	Errors e;
	e.rotationDeg = angleDeg(r.motion.R_cur_ref * s.truth.R_cur_ref.transpose());
	e.directionDeg = angleBetweenDeg(r.motion.t_cur_ref, s.truth.t_cur_ref);
	const double scale = s.truth.t_cur_ref.norm();
	std::vector<double> ratios;
	for (std::size_t i = 0; i < s.X_ref.size(); i++)
	{
		if (s.outlier[i])
		{
			e.validOutliers += r.triangulated[i];
			e.inlierOutliers += r.inliers[i];
			continue;
		}
		if (!r.triangulated[i]) continue;
		e.validInliers++;
		const Eigen::Vector3d& X = s.X_ref[i];
		ratios.push_back((r.points_ref[i] * scale - X).norm() / crb.pointRms[i]);
	}
	if (!ratios.empty())
	{
		std::nth_element(ratios.begin(), ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2), ratios.end());
		e.medianPointError = ratios[ratios.size() / 2];
	}
	return e;
}

/** Upper bound on how many outliers may end in the inlier mask, from the chance that a uniform
 * current pixel passes the gate, as a Poisson mean + 4 sigma (+1). On success the mask is
 * gated on the refined motion's epipolar (Sampson) error for both models: within
 * sqrt(3.84 (2 sigma^2)) = 2.8 px of an epipolar line at most 800 px long (the image
 * diagonal) in a 640 x 480 image, p <= 2 * 2.8 * 800 / 307200 = 1.4 %. */
int outlierBound(const Scene& s)
{
	const double band = 2 * std::sqrt(3.84 * 2) * kSigma * std::hypot(kW, kH);
	const double mean = s.numOutliers * band / (kW * kH);
	return static_cast<int>(std::ceil(mean + 4 * std::sqrt(mean))) + 1;
}

/** The checks shared by the general and planar scenes. Bounds:
 *  - rotation and translation direction within 4x the rms error of an efficient estimator
 *    (Cramer-Rao, per scene). The refined motion minimises the Sampson error of the gated
 *    inliers, within ~1.5x of the bound: 4x the bound is 2.7 of its own rms, exceeded with
 *    probability exp(-2.7^2) < 1e-3 for a 2-dof error. (Over 100 seeds the worst ratios were
 *    2.5 for R and 3.0 for t.)
 *  - the median point error within 4x its own Cramer-Rao rms (the points share the motion's
 *    error; worst median over 100 seeds 2.5).
 *  - all but a binomial 4-sigma tail of the true inliers triangulated (each passes the two
 *    95 % gates: >= 90 %), few outliers accepted (outlierBound). */
void expectAccurate(const Scene& s, const TwoViewResult& r, TwoViewModel model)
{
	ASSERT_TRUE(r.ok) << r.message;
	EXPECT_EQ(r.model, model) << r.message;
	EXPECT_EQ(r.failure, TwoViewFailure::None);
	EXPECT_NEAR(r.motion.t_cur_ref.norm(), 1.0, 1e-12);
	ASSERT_EQ(r.points_ref.size(), s.X_ref.size());
	ASSERT_EQ(r.triangulated.size(), s.X_ref.size());
	ASSERT_EQ(r.inliers.size(), s.X_ref.size());
	const PoseBound crb = cramerRao(s);
	const Errors e = compare(s, r, crb);
	EXPECT_LT(e.rotationDeg, 4 * crb.rotationDeg) << "Cramer-Rao rms " << crb.rotationDeg << " deg; " << r.message;
	EXPECT_LT(e.directionDeg, 4 * crb.directionDeg) << "Cramer-Rao rms " << crb.directionDeg << " deg; " << r.message;
	EXPECT_LT(e.medianPointError, 4.0);
	const int n = static_cast<int>(s.X_ref.size()) - s.numOutliers;
	EXPECT_GE(e.validInliers, 0.9 * n - 4 * std::sqrt(n * 0.9 * 0.1)) << r.message;
	EXPECT_LE(e.inlierOutliers, outlierBound(s)) << s.numOutliers << " outliers";
	EXPECT_LE(e.validOutliers, e.inlierOutliers);
	EXPECT_EQ(r.numTriangulated, static_cast<int>(std::count(r.triangulated.begin(), r.triangulated.end(), uint8_t{1})));
	EXPECT_GE(r.parallaxDeg, TwoViewOptions{}.minParallaxDeg);
}

/** The scene with translation `t` (planar or not) of seeds 1, 2, 3 through the initializer: each
 * result must pass expectAccurate for `model`, and `whySelected(r)` checks the model choice. */
template <class WhySelected>
void expectRecoveredOverSeeds(const Eigen::Vector3d& t, bool planar, TwoViewModel model, WhySelected whySelected)
{
	for (uint32_t seed : {1u, 2u, 3u})
	{
		SCOPED_TRACE(seed);
		const Scene s = makeScene(kR, t, planar, kPoints, kOutlierShare, seed);
		const TwoViewResult r = TwoViewInitializer(kK).initialize(s.matches);
		expectAccurate(s, r, model);
		whySelected(r);
	}
}
}  // namespace

TEST(TwoViewInitializer, GeneralSceneSelectsFundamentalAndRecoversTheMotion)
{
	expectRecoveredOverSeeds(kGeneralT, false, TwoViewModel::Fundamental, [](const TwoViewResult& r) {
		EXPECT_LT(r.ratioH, TwoViewOptions{}.homographyRatio);
	});
}

TEST(TwoViewInitializer, PlanarSceneSelectsHomographyAndRecoversTheMotion)
{
	expectRecoveredOverSeeds(kPlanarT, true, TwoViewModel::Homography, [](const TwoViewResult& r) {
		EXPECT_GE(r.sharedInlierShare, TwoViewOptions{}.homographyInlierShare);
	});
}

TEST(TwoViewInitializer, PureRotationIsRefusedAsLowParallax)
{
	for (bool planar : {false, true})
		for (uint32_t seed : {1u, 2u})
		{
			SCOPED_TRACE(std::string(planar ? "planar" : "3D") + " seed " + std::to_string(seed));
			const Scene s = makeScene(kR, Eigen::Vector3d::Zero(), planar, kPoints, kOutlierShare, seed);
			const TwoViewResult r = TwoViewInitializer(kK).initialize(s.matches);
			EXPECT_FALSE(r.ok);
			EXPECT_EQ(r.failure, TwoViewFailure::LowParallax) << r.message;
			EXPECT_NE(r.message.find("low parallax"), std::string::npos) << r.message;
			EXPECT_TRUE(r.points_ref.empty());
			// The rotation alone is explained by H = K R K^-1: the homography is selected.
			EXPECT_EQ(r.model, TwoViewModel::Homography) << r.message;
		}
}

TEST(TwoViewInitializer, TooFewMatchesAreRefused)
{
	const TwoViewOptions o;
	Scene s = makeScene(kR, kGeneralT, false, o.minMatches - 1, 0.0, 1);
	TwoViewResult r = TwoViewInitializer(kK, o).initialize(s.matches);
	EXPECT_FALSE(r.ok);
	EXPECT_EQ(r.failure, TwoViewFailure::TooFewMatches);
	EXPECT_NE(r.message.find(std::to_string(o.minMatches - 1)), std::string::npos) << r.message;
	// One more is enough to try (and here, to succeed).
	s = makeScene(kR, kGeneralT, false, o.minMatches, 0.0, 1);
	r = TwoViewInitializer(kK, o).initialize(s.matches);
	EXPECT_TRUE(r.ok) << r.message;
	s.matches.px_cur.pop_back();
	EXPECT_THROW(TwoViewInitializer(kK, o).initialize(s.matches), std::invalid_argument);
}

TEST(TwoViewInitializer, SameSeedGivesBitIdenticalResults)
{
	const Scene s = makeScene(kR, kGeneralT, false, kPoints, kOutlierShare, 4);
	TwoViewOptions o;
	const TwoViewResult a = TwoViewInitializer(kK, o).initialize(s.matches);
	const TwoViewResult b = TwoViewInitializer(kK, o).initialize(s.matches);
	o.parallel = false;
	const TwoViewResult c = TwoViewInitializer(kK, o).initialize(s.matches);
	ASSERT_TRUE(a.ok) << a.message;
	for (const TwoViewResult* x : {&b, &c})
	{
		EXPECT_EQ(std::memcmp(a.motion.R_cur_ref.data(), x->motion.R_cur_ref.data(), 9 * sizeof(double)), 0);
		EXPECT_EQ(std::memcmp(a.motion.t_cur_ref.data(), x->motion.t_cur_ref.data(), 3 * sizeof(double)), 0);
		EXPECT_EQ(std::memcmp(a.points_ref.data(), x->points_ref.data(), a.points_ref.size() * sizeof(Eigen::Vector3d)), 0);
		EXPECT_EQ(a.inliers, x->inliers);
		EXPECT_EQ(a.triangulated, x->triangulated);
		EXPECT_EQ(a.scoreH, x->scoreH);
		EXPECT_EQ(a.scoreF, x->scoreF);
		EXPECT_EQ(a.message, x->message);
	}
	// Another seed draws other samples: the scores differ (and the motion agrees within noise).
	o.seed += 1;
	const TwoViewResult d = TwoViewInitializer(kK, o).initialize(s.matches);
	EXPECT_TRUE(d.scoreF != a.scoreF || d.scoreH != a.scoreH);
}

TEST(TwoViewInitializer, DecompositionsContainTheExactMotion)
{
	// Noise-free closed forms: E = [t]_x R and A = R + t n^T / d must decompose into sets that
	// contain (R, t / |t|) to rounding, and every essential hypothesis reproduces E up to sign.
	const Eigen::Vector3d t = kPlanarT;
	Eigen::Matrix3d tx;
	tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
	const Eigen::Matrix3d E = tx * kR;
	const auto closeTo = [&](const RelativeMotion& m) {
		return (m.R_cur_ref - kR).norm() < 1e-9 && (m.t_cur_ref - t.normalized()).norm() < 1e-9;
	};
	const auto es = decomposeEssential(E);
	ASSERT_EQ(es.size(), 4u);
	EXPECT_EQ(std::count_if(es.begin(), es.end(), closeTo), 1);
	for (const auto& m : es)
	{
		Eigen::Matrix3d mx;
		const Eigen::Vector3d& u = m.t_cur_ref;
		mx << 0, -u.z(), u.y(), u.z(), 0, -u.x(), -u.y(), u.x(), 0;
		const Eigen::Matrix3d Em = mx * m.R_cur_ref;
		const double sign = Em.cwiseProduct(E).sum() > 0 ? 1.0 : -1.0;
		EXPECT_LT((sign * Em / Em.norm() - E / E.norm()).norm(), 1e-9);
		EXPECT_NEAR(m.R_cur_ref.determinant(), 1.0, 1e-12);
	}
	const Eigen::Matrix3d A = 2.5 * (kR + t * kPlaneN.transpose() / kPlaneD);  // any scale
	for (double lambda : {1.0, -1.0})  // the DLT's sign is arbitrary
	{
		const auto hs = decomposeHomography(lambda * A);
		ASSERT_EQ(hs.size(), 8u);
		EXPECT_EQ(std::count_if(hs.begin(), hs.end(), closeTo), 1) << "lambda " << lambda;
		for (const auto& m : hs) EXPECT_NEAR(m.R_cur_ref.determinant(), 1.0, 1e-12);
	}
	// A rotation alone has three equal singular values: no decomposition.
	EXPECT_TRUE(decomposeHomography(kR).empty());
}

TEST(TwoViewInitializer, ModelsFitNoiseFreeCorrespondencesExactly)
{
	// The DLT and the 8-point must reproduce the true models from exact data (x_cur ~ H x_ref
	// on the plane; x_cur^T F x_ref = 0 in a 3D scene) to rounding.
	const Scene p = makeScene(kR, kPlanarT, true, 20, 0.0, 5);
	const Eigen::Matrix3d K = cameraMatrix();
	Eigen::Matrix3d Htrue = K * (kR + kPlanarT * kPlaneN.transpose() / kPlaneD) * K.inverse();
	Htrue /= Htrue.norm();
	std::vector<Eigen::Vector2d> a, b;  // exact projections (the scene's pixels are noisy)
	for (const auto& X : p.X_ref)
	{
		a.push_back(project(X));
		b.push_back(project(kR * X + kPlanarT));
	}
	Eigen::Matrix3d H;
	ASSERT_TRUE(homographyDlt(a, b, H));
	EXPECT_LT(std::min((H - Htrue).norm(), (H + Htrue).norm()), 1e-9);
	const Scene g = makeScene(kR, kGeneralT, false, 20, 0.0, 5);
	a.clear();
	b.clear();
	for (const auto& X : g.X_ref)
	{
		a.push_back(project(X));
		b.push_back(project(kR * X + kGeneralT));
	}
	Eigen::Matrix3d F;
	ASSERT_TRUE(fundamentalEightPoint(a, b, F));
	Eigen::Matrix3d tx;
	tx << 0, -kGeneralT.z(), kGeneralT.y(), kGeneralT.z(), 0, -kGeneralT.x(), -kGeneralT.y(), kGeneralT.x(), 0;
	Eigen::Matrix3d Ftrue = K.inverse().transpose() * tx * kR * K.inverse();
	Ftrue /= Ftrue.norm();
	EXPECT_LT(std::min((F - Ftrue).norm(), (F + Ftrue).norm()), 1e-9);
	EXPECT_NEAR(F.jacobiSvd().singularValues()(2), 0.0, 1e-12);
}

TEST(TwoViewInitializer, OptionsAreValidatedAndRead)
{
	TwoViewOptions o;
	EXPECT_TRUE(o.isValid());
	o.homographyRatio = 1.2;
	std::string err;
	EXPECT_FALSE(o.isValid(&err));
	EXPECT_NE(err.find("homography_ratio"), std::string::npos) << err;
	EXPECT_THROW(TwoViewInitializer(kK, o), std::invalid_argument);
	mrpt::config::CConfigFileMemory c;
	c.write("init", "homography_ratio", 0.40);
	c.write("init", "seed", 77);
	TwoViewOptions r;
	r.loadFromConfigFile(c, "init");
	EXPECT_DOUBLE_EQ(r.homographyRatio, 0.40);
	EXPECT_EQ(r.seed, 77u);
	c.write("init", "min_matches", 3);
	EXPECT_THROW(r.loadFromConfigFile(c, "init"), std::invalid_argument);
}

// The two-fold ambiguity of a plane (short baseline, |t| / d = 0.05): refused as Ambiguous,
// with the competing motions as candidates; one of them is the true motion and implies the
// true plane, whose normal (noise-free) is kPlaneN turned towards the camera.
TEST(TwoViewInitializer, AnAmbiguousPlaneListsTheTrueMotionAmongItsCandidates)
{
	// Noise-free correspondences: the true motion and plane come out exactly.
	Scene exact = makeScene(kR, Eigen::Vector3d(0.2, 0.02, 0.02), true, kPoints, 0.0, 4);
	for (std::size_t i = 0; i < exact.X_ref.size(); i++)
	{
		exact.matches.px_ref[i] = project(exact.X_ref[i]);
		exact.matches.px_cur[i] = project(kR * exact.X_ref[i] + Eigen::Vector3d(0.2, 0.02, 0.02));
	}
	const TwoViewResult r = TwoViewInitializer(kK).initialize(exact.matches);
	ASSERT_EQ(r.failure, TwoViewFailure::Ambiguous) << r.message;
	ASSERT_GE(r.candidates.size(), 2u);
	bool foundTruth = false;
	for (const auto& c : r.candidates)
	{
		const double rotErr = Eigen::AngleAxisd(c.motion.R_cur_ref * kR.transpose()).angle() * 180 / M_PI;
		const double dirErr = angleBetweenDeg(c.motion.t_cur_ref, Eigen::Vector3d(0.2, 0.02, 0.02));
		if (rotErr < 1e-3 && dirErr < 1e-3)
		{
			foundTruth = true;
			EXPECT_LT(angleBetweenDeg(c.planeNormal_ref, -kPlaneN), 1e-3);
		}
		EXPECT_NEAR(c.planeNormal_ref.norm(), 1.0, 1e-12);
	}
	EXPECT_TRUE(foundTruth);
}

// The two-fold ambiguity of a plane under sideways travel with little rotation: the second
// solution of the homography puts the plane normal along the travel, a plane seen edge-on,
// and reads the views as nearly a rotation about far points (median parallax a fraction of a
// degree). It could not start a map, so the translating motion is taken and comes out exact;
// with that rule off (rival_parallax_share = 0) the pair stays Ambiguous, as in ORB-SLAM.
// With a rotation of more than rival_max_rotation_ratio times the parallax (the test above:
// 7.5 deg against 2.1) the rule does not apply.
TEST(TwoViewInitializer, ARotationLikeSecondSolutionOfAPlaneIsNoRivalForSidewaysTravel)
{
	const Eigen::Matrix3d R = rotation(0.3, -0.4, 0.8);
	const Eigen::Vector3d t(0.2, 0.02, 0.02);
	for (uint32_t seed : {1u, 2u, 3u})
	{
		SCOPED_TRACE(seed);
		// Noisy correspondences with outliers: as accurate as the other scenes.
		const Scene s = makeScene(R, t, true, kPoints, kOutlierShare, seed);
		expectAccurate(s, TwoViewInitializer(kK).initialize(s.matches), TwoViewModel::Homography);

		// Noise-free: the exact motion; without the rule, Ambiguous with a rotation-like rival.
		Scene exact = makeScene(R, t, true, kPoints, 0.0, seed);
		for (std::size_t i = 0; i < exact.X_ref.size(); i++)
		{
			exact.matches.px_ref[i] = project(exact.X_ref[i]);
			exact.matches.px_cur[i] = project(R * exact.X_ref[i] + t);
		}
		const TwoViewResult r = TwoViewInitializer(kK).initialize(exact.matches);
		ASSERT_TRUE(r.ok) << r.message;
		EXPECT_LT(angleDeg(r.motion.R_cur_ref * R.transpose()), 1e-6);
		EXPECT_LT(angleBetweenDeg(r.motion.t_cur_ref, t), 1e-6);
		TwoViewOptions strict;
		strict.rivalParallaxShare = 0;
		const TwoViewResult a = TwoViewInitializer(kK, strict).initialize(exact.matches);
		EXPECT_EQ(a.failure, TwoViewFailure::Ambiguous) << a.message;
		ASSERT_GE(a.candidates.size(), 2u);
		EXPECT_LT(a.candidates[1].parallaxDeg, strict.minParallaxDeg);
	}
}
}  // namespace two_view_initializer_unittest
