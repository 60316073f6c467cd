#include <keygrid/sfm/LocalBundleAdjuster.h>
#include <keygrid/sfm/LocalMapper.h>
#include <keygrid/sfm/Matcher.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <ceres/ceres.h>
#include <random>

#include "TestData.h"

using namespace keygrid::sfm;
using mrpt::poses::CPose3D;

namespace local_bundle_adjuster_unittest
{
namespace
{
const PinholeIntrinsics K{517.3, 516.5, 318.6, 255.3};

/** Autodiff of the templated costs, padded to 3 rows (mono: third row 0), for comparison. */
void autodiffReference(
	const AnalyticReprojectionCost& c, const double* q, const double* t, const double* p, double r[3], double Jq[12],
	double Jt[9], double Jp[9])
{
	const double* params[3] = {q, t, p};
	std::fill(r, r + 3, 0.0);
	std::fill(Jq, Jq + 12, 0.0);
	std::fill(Jt, Jt + 9, 0.0);
	std::fill(Jp, Jp + 9, 0.0);
	double* J[3] = {Jq, Jt, Jp};
	if (c.hasDepth())
	{
		ceres::AutoDiffCostFunction<RgbdReprojectionCost, 3, 4, 3, 3> ad(
			new RgbdReprojectionCost(c.m_uv, c.m_bf / c.m_disparity, c.m_bf, c.m_invSigma, c.m_invSigmaDisparity, c.m_K));
		ASSERT_TRUE(ad.Evaluate(params, r, J));
	}
	else
	{
		// 2 rows: row-major blocks fill the first rows of the 3-row buffers.
		ceres::AutoDiffCostFunction<MonoReprojectionCost, 2, 4, 3, 3> ad(new MonoReprojectionCost(c.m_uv, c.m_invSigma, c.m_K));
		ASSERT_TRUE(ad.Evaluate(params, r, J));
	}
}
}  // namespace

TEST(AnalyticReprojectionCost, MatchesAutoDiffOfTheTemplatedCosts)
{
	std::mt19937 rng(7);
	std::uniform_real_distribution<double> U(-1.0, 1.0);
	for (int trial = 0; trial < 40; trial++)
	{
		// Random pose; every other trial a quaternion 5 % off unit norm (Ceres' iterates are
		// only approximately unit), which the polynomial Jacobians must also handle.
		Eigen::Quaterniond q(Eigen::AngleAxisd(U(rng), Eigen::Vector3d(U(rng), U(rng), U(rng)).normalized()));
		q.coeffs() *= trial % 2 ? 1.05 : 1.0;
		double qv[4] = {q.x(), q.y(), q.z(), q.w()}, t[3] = {0.2 * U(rng), 0.2 * U(rng), 0.2 * U(rng)};
		double p[3] = {U(rng), U(rng), 2.5 + U(rng)};
		const Eigen::Vector2d uv(320 + 100 * U(rng), 240 + 100 * U(rng));
		const double depth = trial % 3 == 0 ? 0.0 : 2.0 + U(rng);
		const AnalyticReprojectionCost c(uv, depth, 40.0, 1.0 / 1.44, 4.0, K);
		ASSERT_EQ(c.hasDepth(), depth > 0);
		double r[3], Jq[12], Jt[9], Jp[9], rr[3], Rq[12], Rt[9], Rp[9];
		ASSERT_TRUE(c.evaluate(qv, t, p, r, Jq, Jt, Jp));
		autodiffReference(c, qv, t, p, rr, Rq, Rt, Rp);
		for (int k = 0; k < 3; k++) EXPECT_NEAR(r[k], rr[k], 1e-9 * (1 + std::abs(rr[k]))) << "trial " << trial;
		for (int k = 0; k < 12; k++) EXPECT_NEAR(Jq[k], Rq[k], 1e-8 * (1 + std::abs(Rq[k]))) << "trial " << trial << " Jq " << k;
		for (int k = 0; k < 9; k++)
		{
			EXPECT_NEAR(Jt[k], Rt[k], 1e-8 * (1 + std::abs(Rt[k]))) << "trial " << trial << " Jt " << k;
			EXPECT_NEAR(Jp[k], Rp[k], 1e-8 * (1 + std::abs(Rp[k]))) << "trial " << trial << " Jp " << k;
		}
		// Residuals alone (no Jacobians requested) are the same numbers.
		double r2[3];
		ASSERT_TRUE(c.evaluate(qv, t, p, r2, nullptr, nullptr, nullptr));
		for (int k = 0; k < 3; k++) EXPECT_EQ(r[k], r2[k]);
	}
	// Behind the camera: rejected like the templated costs.
	const AnalyticReprojectionCost c({300, 200}, 1.5, 40.0, 1.0, 4.0, K);
	double qv[4] = {0, 0, 0, 1}, t[3] = {0, 0, 0}, p[3] = {0.1, 0.1, -1.0}, r[3];
	EXPECT_FALSE(c.evaluate(qv, t, p, r, nullptr, nullptr, nullptr));
}

TEST(LocalMapper, SubsetMatchingEqualsFilteredBruteForce)
{
	// Random ORB-like descriptors; b holds noisy copies of a's so that there are real matches,
	// duplicated rows create exact ties.
	std::mt19937 rng(3);
	const int n = 300;
	FrameFeatures a, b;
	a.descriptors = cv::Mat(n, 32, CV_8U);
	cv::randu(a.descriptors, 0, 256);
	b.descriptors = a.descriptors.clone();
	for (int i = 0; i < n; i++)
	{
		const int flips = static_cast<int>(rng() % 60);
		for (int f = 0; f < flips; f++) b.descriptors.at<uint8_t>(i, static_cast<int>(rng() % 32)) ^= static_cast<uint8_t>(1u << (rng() % 8));
	}
	a.descriptors.row(5).copyTo(a.descriptors.row(6));
	b.descriptors.row(10).copyTo(b.descriptors.row(11));
	std::vector<int> ia;
	for (int i = 0; i < n; i++)
		if (i % 3 != 1) ia.push_back(i);
	MatcherOptions mo;
	std::vector<std::pair<int, int>> expected;
	for (const auto& m : matchBruteForce(a, b, mo, 0.8f))
		if (std::find(ia.begin(), ia.end(), m.first) != ia.end()) expected.push_back(m);
	const auto got = matchSubsetBruteForce(a, ia, b, mo.maxDistance(true), 0.8f);
	EXPECT_GT(expected.size(), 50u);
	EXPECT_EQ(got, expected);
}

namespace
{
/** Four keyframes observing 80 points (half with depth), exact measurements. */
struct Scene
{
	SparseMap map;
	std::vector<CPose3D> truePoses;
	std::vector<Eigen::Vector3d> truePoints;
};

void buildScene(Scene& s, double poseNoise, double pointNoise)
{
	std::mt19937 rng(11);
	std::uniform_real_distribution<double> U(-1.0, 1.0);
	std::normal_distribution<double> N(0.0, 1.0);
	const int nPts = 80;
	for (int i = 0; i < nPts; i++) s.truePoints.emplace_back(0.8 * U(rng), 0.6 * U(rng), 2.2 + 0.6 * U(rng));
	s.truePoses = {
		CPose3D(0, 0, 0, 0, 0, 0), CPose3D(0.10, 0.01, 0.02, 0.03, 0.01, 0.0), CPose3D(0.2, -0.02, 0.0, 0.05, -0.02, 0.01),
		CPose3D(0.3, 0.0, 0.05, 0.08, 0.0, -0.02)};
	cv::Mat desc(nPts, 32, CV_8U);
	cv::randu(desc, 0, 256);
	for (std::size_t k = 0; k < s.truePoses.size(); k++)
	{
		KeyFrame kf;
		kf.T_world_cam = k == 0 ? s.truePoses[k]
								: s.truePoses[k] + CPose3D(poseNoise * N(rng), poseNoise * N(rng), poseNoise * N(rng),
													   poseNoise * N(rng), poseNoise * N(rng), poseNoise * N(rng));
		auto& f = kf.features;
		f.levelScale = {1.0, 1.2};
		f.numLevels = 2;
		f.descriptors = desc.clone();
		for (int i = 0; i < nPts; i++)
		{
			double x, y, z;
			(-s.truePoses[k]).composePoint(s.truePoints[i].x(), s.truePoints[i].y(), s.truePoints[i].z(), x, y, z);
			cv::KeyPoint kp(static_cast<float>(K.fx * x / z + K.cx), static_cast<float>(K.fy * y / z + K.cy), 8.f);
			kp.octave = i % 2;
			f.keypoints.push_back(kp);
			f.undistorted.emplace_back(static_cast<float>(K.fx * x / z + K.cx), static_cast<float>(K.fy * y / z + K.cy));
			f.depth.push_back(i % 2 == 0 ? static_cast<float>(z) : 0.f);
		}
		s.map.addKeyFrame(std::move(kf));
	}
	for (int i = 0; i < nPts; i++)
	{
		const Eigen::Vector3d p0 = s.truePoints[i] + pointNoise * Eigen::Vector3d(N(rng), N(rng), N(rng));
		const LandmarkId id = s.map.addLandmark(p0, 0, i);
		for (KeyFrameId k = 1; k < s.truePoses.size(); k++) s.map.addObservation(id, k, i);
	}
	for (KeyFrameId k = 0; k < s.truePoses.size(); k++) s.map.updateCovisibility(k);
}
}  // namespace

TEST(LocalBundleAdjuster, RecoversTheSceneWithEverySolverAndJacobian)
{
	// Exact measurements (up to float pixels), perturbed start: every solver / Jacobian variant
	// must return to the ground truth.
	std::vector<CPose3D> results;
	// Auto runs this window (it has depth measurements) on the dedicated solver, as Dedicated
	// does with either Jacobian flag; the others are Ceres'.
	for (const auto solver : {BaLinearSolver::Auto, BaLinearSolver::DenseSchur, BaLinearSolver::SparseSchur, BaLinearSolver::IterativeSchur,
			 BaLinearSolver::Dedicated})
		for (bool analytic : {true, false})
		{
			Scene s;
			buildScene(s, 0.01, 0.02);
			BundleAdjusterOptions o;
			o.linearSolver = solver;
			o.analyticJacobians = analytic;
			o.iterations = 30;
			o.bf = 40.0;
			const auto rep = localBundleAdjustment(s.map, 3, K, o);
			EXPECT_EQ(rep.dedicatedSolver, solver == BaLinearSolver::Dedicated || (solver == BaLinearSolver::Auto && analytic))
				<< "solver " << int(solver) << " analytic " << analytic;
			EXPECT_EQ(rep.keyframes, 4);
			EXPECT_EQ(rep.landmarks, 80);
			EXPECT_EQ(rep.observations, 320);
			EXPECT_EQ(rep.outliersRemoved, 0);
			EXPECT_LT(rep.finalCost, 1e-3 * rep.initialCost);
			// Keyframe 0 is the gauge and stays put; the others return to the truth.
			for (KeyFrameId k = 0; k < 4; k++)
			{
				const CPose3D& T = s.map.keyframe(k).T_world_cam;
				EXPECT_LT((T - s.truePoses[k]).translation().norm(), 2e-4) << "kf " << k << " solver " << int(solver) << " analytic " << analytic;
				const Eigen::Matrix3d dR = (T - s.truePoses[k]).getRotationMatrix().asEigen();
				EXPECT_LT(std::acos(std::min(1.0, (dR.trace() - 1.0) / 2.0)), 1e-4) << "kf " << k;
			}
			for (int i = 0; i < 80; i++) EXPECT_LT((s.map.landmark(static_cast<LandmarkId>(i)).p_world - s.truePoints[i]).norm(), 1e-3);
			results.push_back(s.map.keyframe(3).T_world_cam);
		}
	// Analytic and autodiff Jacobians, any linear solver: the same optimum.
	for (const auto& r : results) EXPECT_LT((r - results.front()).translation().norm(), 1e-6);
}

TEST(LocalBundleAdjuster, AutoKeepsCeresForAWindowWithoutDepth)
{
	// The same window with every depth beyond max_depth_for_rgbd (the points are 1.6-2.8 m
	// away): all of it monocular, so `auto` solves it with Ceres' dense Schur, `dedicated` not.
	for (const auto solver : {BaLinearSolver::Auto, BaLinearSolver::Dedicated})
	{
		Scene s;
		buildScene(s, 0.01, 0.02);
		BundleAdjusterOptions o;
		o.linearSolver = solver;
		o.maxDepthForRgbd = 1.0;
		o.bf = 40.0;
		const auto rep = localBundleAdjustment(s.map, 3, K, o);
		EXPECT_EQ(rep.observations, 320);
		EXPECT_EQ(rep.dedicatedSolver, solver == BaLinearSolver::Dedicated) << "solver " << int(solver);
		EXPECT_LT(rep.finalCost, rep.initialCost);
	}
}

TEST(LocalBundleAdjuster, FunctionToleranceEndsTheSolveOnceAnIterationGainsLittle)
{
	// Noisy measurements (1 px): the cost has a floor well above zero. With tolerance 0 the
	// solve runs until the parameters stop moving (Ceres' parameter tolerance; 7 iterations
	// here); with 0.5 it stops at the first iteration that lowers the cost by less than half,
	// short of the floor; the default 1e-3 stops earlier than the full solve yet within 1 % of
	// its cost.
	auto solve = [](double tol)
	{
		Scene s;
		buildScene(s, 0.02, 0.05);
		std::mt19937 rng(3);
		std::normal_distribution<double> N(0.0, 1.0);
		for (KeyFrameId k = 0; k < 4; k++)
			for (auto& uv : s.map.keyframe(k).features.undistorted) uv += cv::Point2f(static_cast<float>(N(rng)), static_cast<float>(N(rng)));
		BundleAdjusterOptions o;
		o.iterations = 25;
		o.functionTolerance = tol;
		o.chi2Mono = o.chi2Rgbd = 1e9;  // keep every observation: the costs compare like for like
		return localBundleAdjustment(s.map, 3, K, o);
	};
	const auto full = solve(0.0), loose = solve(0.5), dflt = solve(1e-3);
	EXPECT_LT(loose.iterations, full.iterations);
	EXPECT_GE(loose.iterations, 1);
	EXPECT_GT(loose.finalCost, 1.05 * full.finalCost);
	EXPECT_LT(dflt.iterations, full.iterations);
	EXPECT_LT(dflt.finalCost, 1.01 * full.finalCost);
	EXPECT_LT(full.finalCost, 0.5 * full.initialCost);
}

TEST(LocalBundleAdjuster, RemovesAGrossOutlierObservation)
{
	Scene s;
	buildScene(s, 0.005, 0.005);
	// Keypoint 4 of keyframe 2 moved by 40 px: its observation must go, nothing else.
	s.map.keyframe(2).features.undistorted[4].x += 40.f;
	BundleAdjusterOptions o;
	o.iterations = 30;
	const auto rep = localBundleAdjustment(s.map, 3, K, o);
	EXPECT_EQ(rep.outliersRemoved, 1);
	EXPECT_EQ(s.map.landmark(4).observations.count(2), 0u);
	// One solve: the outlier's Huber-bounded pull stays in the poses (1.2 mm here since the depth
	// residual no longer re-counts the u error of RGB-D observations; the start error is 5 mm).
	EXPECT_LT((s.map.keyframe(2).T_world_cam - s.truePoses[2]).translation().norm(), 2e-3);
}

TEST(LocalBundleAdjuster, APointBehindTheCamerasIsDroppedInsteadOfStoppingTheSolve)
{
	// One landmark starts behind every camera: its residuals cannot be evaluated, which used
	// to make Ceres abandon the whole adjustment (the poses stayed perturbed).
	Scene s;
	buildScene(s, 0.01, 0.02);
	s.map.landmark(5).p_world = Eigen::Vector3d(0.1, 0.0, -2.0);
	BundleAdjusterOptions o;
	o.iterations = 30;
	const auto rep = localBundleAdjustment(s.map, 3, K, o);
	EXPECT_EQ(rep.observations, 316);
	EXPECT_EQ(rep.outliersRemoved, 4);
	EXPECT_FALSE(s.map.hasLandmark(5));
	for (KeyFrameId k = 1; k < 4; k++)
		EXPECT_LT((s.map.keyframe(k).T_world_cam - s.truePoses[k]).translation().norm(), 2e-4) << "kf " << k;
}

namespace
{
/** Largest angle [deg] at landmark `id` between the centres of two keyframes observing it, from
 * the law of cosines on the triangle they form. */
double largestParallaxDeg(const SparseMap& map, LandmarkId id)
{
	const Eigen::Vector3d P = map.landmark(id).p_world;
	std::vector<Eigen::Vector3d> centres;
	for (const auto& [kf, kp] : map.landmark(id).observations)
	{
		const auto t = map.keyframe(kf).T_world_cam.translation();
		centres.emplace_back(t.x, t.y, t.z);
	}
	double best = 0;
	for (std::size_t i = 0; i < centres.size(); i++)
		for (std::size_t j = i + 1; j < centres.size(); j++)
		{
			const double a = (P - centres[i]).norm(), b = (P - centres[j]).norm(), c = (centres[i] - centres[j]).norm();
			best = std::max(best, std::acos((a * a + b * b - c * c) / (2 * a * b)) * 180.0 / M_PI);
		}
	return best;
}
}  // namespace

TEST(LocalBundleAdjuster, ALandmarkWithoutDepthOrParallaxStaysOut)
{
	// The landmarks without depth (odd ids) are seen by keyframes 0 and 3 only; landmark 1 is
	// moved 5 cm off. At a threshold just below landmark 1's parallax it takes part (and returns
	// to the truth), just above it it stays out (and where it is); either way exactly the
	// landmarks without depth whose parallax is below the threshold stay out.
	for (const double delta : {-0.01, 0.01})
	{
		Scene s;
		buildScene(s, 0.0, 0.0);
		for (LandmarkId id = 1; id < 80; id += 2)
		{
			s.map.eraseObservation(id, 1);
			s.map.eraseObservation(id, 2);
		}
		s.map.landmark(1).p_world += Eigen::Vector3d(0.03, -0.02, 0.035);
		const Eigen::Vector3d P = s.map.landmark(1).p_world;
		const double threshold = largestParallaxDeg(s.map, 1) + delta;
		int expectedOut = 0;
		for (LandmarkId id = 1; id < 80; id += 2) expectedOut += largestParallaxDeg(s.map, id) < threshold;
		ASSERT_GT(threshold, 1.0);
		BundleAdjusterOptions o;
		o.iterations = 30;
		o.minParallaxDegWithoutDepth = threshold;
		const auto rep = localBundleAdjustment(s.map, 3, K, o);
		EXPECT_EQ(rep.landmarksLeftOut, expectedOut);
		EXPECT_EQ(rep.landmarks, 80 - expectedOut);
		if (delta > 0)
			EXPECT_EQ(s.map.landmark(1).p_world, P);
		else
			EXPECT_LT((s.map.landmark(1).p_world - s.truePoints[1]).norm(), 1e-3);
	}
	// A landmark with a depth measurement takes part at any threshold: at 90 degrees only the 40
	// landmarks without depth (odd ids) stay out.
	Scene s;
	buildScene(s, 0.01, 0.02);
	BundleAdjusterOptions o;
	o.iterations = 30;
	o.minParallaxDegWithoutDepth = 90.0;
	const auto rep = localBundleAdjustment(s.map, 3, K, o);
	EXPECT_EQ(rep.landmarksLeftOut, 40);
	EXPECT_EQ(rep.landmarks, 40);
	for (KeyFrameId k = 1; k < 4; k++)
		EXPECT_LT((s.map.keyframe(k).T_world_cam - s.truePoses[k]).translation().norm(), 2e-4) << "kf " << k;
}

TEST(LocalBundleAdjuster, SolvedApartFromTheMapAndAppliedToWhatIsStillThere)
{
	// Threaded mode's sequence: build from the map, let tracking change the map (a landmark
	// erased, one moved by hand), solve without the map, write back.
	Scene s, ref;
	buildScene(s, 0.01, 0.02);
	buildScene(ref, 0.01, 0.02);
	BundleAdjusterOptions o;
	o.iterations = 30;
	auto ba = BundleAdjustment::around(s.map, 3, K, o);
	s.map.eraseLandmark(7);
	s.map.landmark(8).p_world = Eigen::Vector3d(9, 9, 9);
	ba.solve();
	const auto rep = ba.apply(s.map);
	// The result is the one-step adjustment's (built from the same state)...
	const auto repRef = localBundleAdjustment(ref.map, 3, K, o);
	EXPECT_EQ(rep.observations, repRef.observations);
	EXPECT_DOUBLE_EQ(rep.finalCost, repRef.finalCost);
	for (KeyFrameId k = 1; k < 4; k++)
		EXPECT_LT((s.map.keyframe(k).T_world_cam - ref.map.keyframe(k).T_world_cam).translation().norm(), 1e-12);
	// ...the erased landmark stays erased, the other one gets the solved position.
	EXPECT_FALSE(s.map.hasLandmark(7));
	EXPECT_LT((s.map.landmark(8).p_world - s.truePoints[8]).norm(), 1e-3);
	EXPECT_EQ(s.map.numLandmarks(), 79u);
}

TEST(LocalBundleAdjuster, OptionsRoundTripAndRejectUnknownSolver)
{
	mrpt::config::CConfigFileMemory saved;
	BundleAdjusterOptions o;
	o.linearSolver = BaLinearSolver::IterativeSchur;
	o.analyticJacobians = false;
	o.functionTolerance = 0.02;
	o.saveToConfigFile(saved, "mapping");
	// Read back from the text, as a file would be.
	std::string text;
	saved.getContent(text);
	mrpt::config::CConfigFileMemory cfg(text);
	BundleAdjusterOptions back;
	back.loadFromConfigFile(cfg, "mapping");
	EXPECT_EQ(back.linearSolver, BaLinearSolver::IterativeSchur);
	EXPECT_FALSE(back.analyticJacobians);
	EXPECT_DOUBLE_EQ(back.functionTolerance, 0.02);
	for (const char* bad : {"1", "-0.1"})
	{
		cfg = mrpt::config::CConfigFileMemory(std::string("[mapping]\nfunction_tolerance = ") + bad + "\n");
		EXPECT_THROW(back.loadFromConfigFile(cfg, "mapping"), std::invalid_argument) << bad;
	}
	cfg = mrpt::config::CConfigFileMemory("[mapping]\nlinear_solver = dedicated\n");
	BundleAdjusterOptions dedicated;
	dedicated.loadFromConfigFile(cfg, "mapping");
	EXPECT_EQ(dedicated.linearSolver, BaLinearSolver::Dedicated);
	cfg = mrpt::config::CConfigFileMemory("[mapping]\nlinear_solver = cholmod\n");
	try
	{
		back.loadFromConfigFile(cfg, "mapping");
		FAIL() << "no exception";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("[mapping] linear_solver = 'cholmod'"), std::string::npos) << e.what();
	}
}

TEST(LocalMapper, PhasesGiveTheResultOfProcessAndDropASolveAcrossACorrection)
{
	// Threaded mode's phases (prepare, solve apart from the map, complete) against process() on
	// the same map: the same map afterwards; a loop correction during the solve drops its result.
	Scene inOneGo, inPhases, corrected;
	for (Scene* s : {&inOneGo, &inPhases, &corrected}) buildScene(*s, 0.01, 0.02);
	LocalMapperOptions o;
	o.ba.iterations = 30;
	LocalMapper oneGo(inOneGo.map, o, {}), phases(inPhases.map, o, {}), dropping(corrected.map, o, {});
	const auto repOneGo = oneGo.process(3, K);
	auto pass = phases.prepare(3, K);
	pass.solve();
	const auto repPhases = phases.complete(std::move(pass));
	EXPECT_FALSE(repPhases.baDiscarded);
	EXPECT_GT(repPhases.ba.observations, 0);
	EXPECT_EQ(repPhases.ba.observations, repOneGo.ba.observations);
	EXPECT_EQ(repPhases.ba.finalCost, repOneGo.ba.finalCost);
	EXPECT_EQ(repPhases.culledKeyFrames, repOneGo.culledKeyFrames);
	ASSERT_EQ(inPhases.map.numKeyFrames(), inOneGo.map.numKeyFrames());
	for (const auto& [id, kf] : inOneGo.map.keyframes()) EXPECT_TRUE(inPhases.map.keyframe(id).T_world_cam == kf.T_world_cam) << "kf " << id;
	ASSERT_EQ(inPhases.map.numLandmarks(), inOneGo.map.numLandmarks());
	for (const auto& [id, lm] : inOneGo.map.landmarks()) EXPECT_EQ(inPhases.map.landmark(id).p_world, lm.p_world) << "landmark " << id;
	const auto stages = [](const LocalMappingReport& r) {
		std::vector<std::string> names;
		for (const auto& [name, seconds] : r.stageSeconds) names.push_back(name);
		return names;
	};
	EXPECT_EQ(stages(repOneGo), (std::vector<std::string>{"cull", "triangulate", "fuse", "ba", "cull_keyframes"}));
	EXPECT_EQ(stages(repPhases), (std::vector<std::string>{"cull", "triangulate", "fuse", "ba_build", "ba_solve", "ba_apply", "cull_keyframes"}));

	const CPose3D before = corrected.map.keyframe(3).T_world_cam;
	auto dropped = dropping.prepare(3, K);
	corrected.map.noteCorrection();  // a loop closed while the solve ran
	dropped.solve();
	const auto repDropped = dropping.complete(std::move(dropped));
	EXPECT_TRUE(repDropped.baDiscarded);
	EXPECT_EQ(repDropped.ba.observations, 0);
	EXPECT_TRUE(corrected.map.keyframe(3).T_world_cam == before);
}
}  // namespace local_bundle_adjuster_unittest
