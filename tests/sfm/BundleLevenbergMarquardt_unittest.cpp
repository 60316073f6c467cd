// The dedicated bundle solver against exact data, against Ceres on the same robust cost
// (autodiff of the templated residuals, quaternion manifold, Huber loss: an independent
// implementation), and through BundleAdjustment on a map of more keyframes than the local
// windows, against the Ceres sparse Schur solve of the same map.
#include <keygrid/sfm/BundleLevenbergMarquardt.h>
#include <keygrid/sfm/LocalBundleAdjuster.h>

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace keygrid::sfm;

namespace bundle_levenberg_marquardt_unittest
{
namespace
{
const PinholeIntrinsics K{517.3, 516.5, 318.6, 255.3};
constexpr double kBf = 40.0, kDisparitySigma = 0.25;

struct BundleProblem
{
	std::vector<BundleCamera> trueCameras, cameras;
	std::vector<Eigen::Vector3d> truePoints, points;
	std::vector<BundleTerm> terms;
};

/** Cameras on an arc around a cloud of points, each looking at its centre; camera 0 fixed.
 * Every point is observed by the cameras it projects into; every third observation has no
 * depth. `outliers`: that many observations moved 25 px. The start is perturbed. */
BundleProblem makeProblem(int nCameras, int nPoints, double pixelNoise, int outliers, double huber, unsigned seed)
{
	BundleProblem p;
	std::mt19937 g(seed);
	std::uniform_real_distribution<double> U(-1.0, 1.0);
	std::normal_distribution<double> N(0.0, 1.0);
	for (int i = 0; i < nCameras; i++)
	{
		const double a = 0.5 * (i - 0.5 * (nCameras - 1)) / nCameras;  // +-0.25 rad around the cloud
		const Eigen::Vector3d c(3 * std::sin(a), 0.1 * U(g), 3 - 3 * std::cos(a));
		const Eigen::Matrix3d R_world_cam = Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitY()).toRotationMatrix();
		BundleCamera cam;
		cam.R_cam_world = R_world_cam.transpose();
		cam.t_cam_world = -cam.R_cam_world * c;
		cam.fixed = i == 0;
		p.trueCameras.push_back(cam);
	}
	for (int j = 0; j < nPoints; j++) p.truePoints.emplace_back(U(g), 0.7 * U(g), 3 + U(g));
	int term = 0;
	for (int j = 0; j < nPoints; j++)
		for (int i = 0; i < nCameras; i++)
		{
			const auto& cam = p.trueCameras[static_cast<std::size_t>(i)];
			const Eigen::Vector3d pc = cam.R_cam_world * p.truePoints[static_cast<std::size_t>(j)] + cam.t_cam_world;
			const double u = K.fx * pc.x() / pc.z() + K.cx, v = K.fy * pc.y() / pc.z() + K.cy;
			if (pc.z() < 0.5 || u < 0 || u > 640 || v < 0 || v > 480) continue;
			BundleTerm t;
			t.camera = i;
			t.point = j;
			const bool outlier = term < outliers * 7 && term % 7 == 3;
			t.uv = Eigen::Vector2d(u + pixelNoise * N(g), v + pixelNoise * N(g)) + (outlier ? Eigen::Vector2d(25, -25) : Eigen::Vector2d::Zero());
			t.invSigma = 1.0 / std::pow(1.2, term % 3);
			if (term % 3 != 0)
			{
				t.disparity = kBf / (pc.z() * (1.0 + 0.002 * pixelNoise * N(g)));
				t.invSigmaDisparity = 1.0 / kDisparitySigma;
			}
			t.huberDelta = huber;
			p.terms.push_back(t);
			term++;
		}
	p.cameras = p.trueCameras;
	for (std::size_t i = 1; i < p.cameras.size(); i++)
	{
		p.cameras[i].R_cam_world = Eigen::AngleAxisd(0.01, Eigen::Vector3d(U(g), U(g), U(g)).normalized()).toRotationMatrix() *
								   p.cameras[i].R_cam_world;
		p.cameras[i].t_cam_world += 0.02 * Eigen::Vector3d(U(g), U(g), U(g));
	}
	p.points = p.truePoints;
	for (auto& x : p.points) x += 0.03 * Eigen::Vector3d(U(g), U(g), U(g));
	return p;
}

/** Ceres on the same cost from the same start: RgbdReprojectionCost / MonoReprojectionCost
 * (autodiff), EigenQuaternionManifold, HuberLoss, sparse Schur; tight tolerances. */
double solveWithCeres(std::vector<BundleCamera>& cameras, std::vector<Eigen::Vector3d>& points, const std::vector<BundleTerm>& terms)
{
	std::vector<std::array<double, 7>> x(cameras.size());
	for (std::size_t i = 0; i < cameras.size(); i++)
	{
		const Eigen::Quaterniond q(cameras[i].R_cam_world);
		const auto& t = cameras[i].t_cam_world;
		x[i] = {q.x(), q.y(), q.z(), q.w(), t.x(), t.y(), t.z()};
	}
	ceres::Problem problem;
	for (std::size_t i = 0; i < cameras.size(); i++)
	{
		problem.AddParameterBlock(x[i].data(), 4, new ceres::EigenQuaternionManifold());
		problem.AddParameterBlock(x[i].data() + 4, 3);
		if (cameras[i].fixed)
		{
			problem.SetParameterBlockConstant(x[i].data());
			problem.SetParameterBlockConstant(x[i].data() + 4);
		}
	}
	for (const auto& t : terms)
	{
		auto& pose = x[static_cast<std::size_t>(t.camera)];
		double* point = points[static_cast<std::size_t>(t.point)].data();
		ceres::LossFunction* loss = t.huberDelta > 0 ? new ceres::HuberLoss(t.huberDelta) : nullptr;
		if (t.disparity > 0)
			problem.AddResidualBlock(
				new ceres::AutoDiffCostFunction<RgbdReprojectionCost, 3, 4, 3, 3>(
					new RgbdReprojectionCost(t.uv, kBf / t.disparity, kBf, t.invSigma, t.invSigmaDisparity, K)),
				loss, pose.data(), pose.data() + 4, point);
		else
			problem.AddResidualBlock(
				new ceres::AutoDiffCostFunction<MonoReprojectionCost, 2, 4, 3, 3>(new MonoReprojectionCost(t.uv, t.invSigma, K)), loss,
				pose.data(), pose.data() + 4, point);
	}
	ceres::Solver::Options so;
	so.linear_solver_type = ceres::SPARSE_SCHUR;
	so.max_num_iterations = 200;
	so.function_tolerance = 1e-14;
	so.gradient_tolerance = 1e-14;
	so.parameter_tolerance = 1e-14;
	ceres::Solver::Summary summary;
	ceres::Solve(so, &problem, &summary);
	for (std::size_t i = 0; i < cameras.size(); i++)
	{
		cameras[i].R_cam_world = Eigen::Quaterniond(x[i][3], x[i][0], x[i][1], x[i][2]).normalized().toRotationMatrix();
		cameras[i].t_cam_world = Eigen::Vector3d(x[i][4], x[i][5], x[i][6]);
	}
	return summary.final_cost;
}

double rotationAngle(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B)
{
	return Eigen::AngleAxisd(A * B.transpose()).angle();
}

BundleSolverOptions tight()
{
	BundleSolverOptions o;
	o.maxIterations = 200;
	o.functionTolerance = 1e-14;
	o.gradientTolerance = 1e-14;
	o.parameterTolerance = 1e-14;
	return o;
}
}  // namespace

TEST(BundleLevenbergMarquardt, ExactDataGiveTheTrueSceneBack)
{
	auto p = makeProblem(8, 150, 0.0, 0, 0.0, 1);
	ASSERT_GT(p.terms.size(), 800u);
	const auto s = solveBundleLevenbergMarquardt(p.cameras, p.points, p.terms, K, kBf, tight());
	EXPECT_TRUE(s.usable);
	EXPECT_GT(s.initialCost, 1e3);
	EXPECT_LT(s.finalCost, 1e-12 * s.initialCost);
	// Camera 0 fixes the gauge (and the scale: the depths); everything returns to the truth.
	for (std::size_t i = 0; i < p.cameras.size(); i++)
	{
		EXPECT_LT(rotationAngle(p.cameras[i].R_cam_world, p.trueCameras[i].R_cam_world), 1e-8) << "camera " << i;
		EXPECT_LT((p.cameras[i].t_cam_world - p.trueCameras[i].t_cam_world).norm(), 1e-8) << "camera " << i;
	}
	for (std::size_t j = 0; j < p.points.size(); j++) EXPECT_LT((p.points[j] - p.truePoints[j]).norm(), 1e-8) << "point " << j;
	// The squared residual of a measurement 3, 4 px off, at sigma 1 and without depth: 25.
	BundleTerm t = p.terms.front();
	t.uv += Eigen::Vector2d(3, 4);
	t.invSigma = 1.0;
	t.disparity = 0;
	double sq = 0;
	ASSERT_TRUE(bundleResidualSquaredNorm(p.cameras[static_cast<std::size_t>(t.camera)], p.points[static_cast<std::size_t>(t.point)], t, K, kBf, sq));
	EXPECT_NEAR(sq, 25.0, 1e-9);
}

TEST(BundleLevenbergMarquardt, ReachesCeresOptimumOnTheSameRobustCost)
{
	// Noise and outliers, Huber at sqrt(7.815): the cost's minimum is what both must find.
	auto p = makeProblem(10, 200, 1.0, 12, std::sqrt(7.815), 2);
	auto cCeres = p.cameras;
	auto xCeres = p.points;
	const double ceresCost = solveWithCeres(cCeres, xCeres, p.terms);
	const auto s = solveBundleLevenbergMarquardt(p.cameras, p.points, p.terms, K, kBf, tight());
	EXPECT_NEAR(s.finalCost, ceresCost, 1e-9 * ceresCost);
	for (std::size_t i = 0; i < p.cameras.size(); i++)
	{
		EXPECT_LT(rotationAngle(p.cameras[i].R_cam_world, cCeres[i].R_cam_world), 1e-7) << "camera " << i;
		EXPECT_LT((p.cameras[i].t_cam_world - cCeres[i].t_cam_world).norm(), 1e-7) << "camera " << i;
	}
	for (std::size_t j = 0; j < p.points.size(); j++) EXPECT_LT((p.points[j] - xCeres[j]).norm(), 1e-6) << "point " << j;
}

TEST(BundleLevenbergMarquardt, RunsAreBitIdentical)
{
	auto a = makeProblem(6, 120, 1.0, 5, std::sqrt(5.991), 3);
	auto b = a;
	const auto sa = solveBundleLevenbergMarquardt(a.cameras, a.points, a.terms, K, kBf);
	const auto sb = solveBundleLevenbergMarquardt(b.cameras, b.points, b.terms, K, kBf);
	EXPECT_EQ(sa.finalCost, sb.finalCost);
	EXPECT_EQ(sa.iterations, sb.iterations);
	for (std::size_t i = 0; i < a.cameras.size(); i++)
	{
		EXPECT_EQ(a.cameras[i].R_cam_world, b.cameras[i].R_cam_world);
		EXPECT_EQ(a.cameras[i].t_cam_world, b.cameras[i].t_cam_world);
	}
	for (std::size_t j = 0; j < a.points.size(); j++) EXPECT_EQ(a.points[j], b.points[j]);
}

TEST(BundleLevenbergMarquardt, APointBehindACameraAtTheStartLeavesEverythingAsItWas)
{
	auto p = makeProblem(4, 40, 0.5, 0, 0.0, 4);
	const auto j = static_cast<std::size_t>(p.terms.front().point);
	const auto& cam = p.cameras[static_cast<std::size_t>(p.terms.front().camera)];
	// Mirror the point through the camera centre: it is now behind that camera.
	const Eigen::Vector3d centre = -cam.R_cam_world.transpose() * cam.t_cam_world;
	p.points[j] = 2 * centre - p.points[j];
	const auto before = p;
	const auto s = solveBundleLevenbergMarquardt(p.cameras, p.points, p.terms, K, kBf);
	EXPECT_FALSE(s.usable);
	EXPECT_EQ(s.iterations, 0);
	for (std::size_t i = 0; i < p.cameras.size(); i++) EXPECT_EQ(p.cameras[i].t_cam_world, before.cameras[i].t_cam_world);
	for (std::size_t k = 0; k < p.points.size(); k++) EXPECT_EQ(p.points[k], before.points[k]);
}

TEST(BundleLevenbergMarquardt, RefusesTermsOutOfRangeOrOutOfOrder)
{
	auto p = makeProblem(3, 20, 0.0, 0, 0.0, 5);
	auto bad = p.terms;
	bad[3].camera = 7;
	EXPECT_THROW(solveBundleLevenbergMarquardt(p.cameras, p.points, bad, K, kBf), std::invalid_argument);
	bad = p.terms;
	bad[2].point = static_cast<int>(p.points.size());
	EXPECT_THROW(solveBundleLevenbergMarquardt(p.cameras, p.points, bad, K, kBf), std::invalid_argument);
	bad = p.terms;
	std::swap(bad.front(), bad.back());
	EXPECT_THROW(solveBundleLevenbergMarquardt(p.cameras, p.points, bad, K, kBf), std::invalid_argument);
}

namespace
{
/** A map of `n` keyframes 5 cm apart along x, all facing a textured wall at z = 3; exact
 * measurements (depth on every other keypoint), then a perturbed start. */
void makeLongMap(SparseMap& map, int n, unsigned seed)
{
	using mrpt::poses::CPose3D;
	std::mt19937 g(seed);
	std::uniform_real_distribution<double> U(-1.0, 1.0);
	std::vector<Eigen::Vector3d> wall;
	for (int j = 0; j < 16 * n; j++) wall.emplace_back(-1.2 + (0.05 * n + 2.4) * (0.5 + 0.5 * U(g)), 0.9 * U(g), 3.0 + 0.3 * U(g));
	std::vector<std::vector<std::pair<int, int>>> seenBy(wall.size());  // point -> (keyframe, keypoint)
	for (int k = 0; k < n; k++)
	{
		const CPose3D T_true(0.05 * k, 0.01 * std::sin(k), 0, 0.02 * std::sin(0.3 * k), 0, 0);
		KeyFrame kf;
		kf.T_world_cam = k == 0 ? T_true : T_true + CPose3D(0.01 * U(g), 0.01 * U(g), 0.01 * U(g), 0.005 * U(g), 0.005 * U(g), 0.005 * U(g));
		auto& f = kf.features;
		f.levelScale = {1.0, 1.2};
		f.numLevels = 2;
		for (std::size_t j = 0; j < wall.size(); j++)
		{
			double x, y, z;
			(-T_true).composePoint(wall[j].x(), wall[j].y(), wall[j].z(), x, y, z);
			const double u = K.fx * x / z + K.cx, v = K.fy * y / z + K.cy;
			if (z < 0.5 || u < 5 || u > 635 || v < 5 || v > 475) continue;
			const int kp = static_cast<int>(f.keypoints.size());
			cv::KeyPoint key(static_cast<float>(u), static_cast<float>(v), 8.f);
			key.octave = kp % 2;
			f.keypoints.push_back(key);
			// Double-precision measurements: the optimum is the truth up to float rounding of uv.
			f.undistorted.emplace_back(static_cast<float>(u), static_cast<float>(v));
			f.depth.push_back(kp % 2 == 0 ? static_cast<float>(z) : 0.f);
			seenBy[j].emplace_back(k, kp);
		}
		f.descriptors = cv::Mat::zeros(static_cast<int>(f.keypoints.size()), 32, CV_8U);
		map.addKeyFrame(std::move(kf));
	}
	for (std::size_t j = 0; j < wall.size(); j++)
	{
		if (seenBy[j].size() < 2) continue;
		const LandmarkId id = map.addLandmark(wall[j] + 0.02 * Eigen::Vector3d(U(g), U(g), U(g)),
			static_cast<KeyFrameId>(seenBy[j][0].first), seenBy[j][0].second);
		for (std::size_t o = 1; o < seenBy[j].size(); o++)
			map.addObservation(id, static_cast<KeyFrameId>(seenBy[j][o].first), seenBy[j][o].second);
	}
	for (int k = 0; k < n; k++) map.updateCovisibility(static_cast<KeyFrameId>(k));
}
}  // namespace

TEST(BundleLevenbergMarquardt, AGlobalAdjustmentOfALongMapMatchesCeresSparseSchur)
{
	// 64 keyframes: more than the local windows, so `auto` takes the dedicated solver; the same
	// map solved by Ceres' sparse Schur must end at the same optimum.
	SparseMap dedicated, ceresMap;
	makeLongMap(dedicated, 64, 9);
	makeLongMap(ceresMap, 64, 9);
	BundleAdjusterOptions o;
	o.iterations = 100;
	o.functionTolerance = 1e-12;
	const auto a = globalBundleAdjustment(dedicated, K, o);
	o.linearSolver = BaLinearSolver::SparseSchur;
	const auto b = globalBundleAdjustment(ceresMap, K, o);
	EXPECT_EQ(a.keyframes, 64);
	EXPECT_EQ(a.observations, b.observations);
	EXPECT_GT(a.observations, 5000);
	EXPECT_EQ(a.outliersRemoved, 0);
	EXPECT_EQ(b.outliersRemoved, 0);
	EXPECT_LT(a.finalCost, 1e-6 * a.initialCost);
	EXPECT_NEAR(a.finalCost, b.finalCost, 1e-9 * a.initialCost);
	for (const auto& [id, kf] : dedicated.keyframes())
	{
		const auto d = kf.T_world_cam - ceresMap.keyframe(id).T_world_cam;
		EXPECT_LT(d.translation().norm(), 1e-7) << "keyframe " << id;
	}
	for (const auto& [id, lm] : dedicated.landmarks()) EXPECT_LT((lm.p_world - ceresMap.landmark(id).p_world).norm(), 1e-6) << "landmark " << id;
}
}  // namespace bundle_levenberg_marquardt_unittest
