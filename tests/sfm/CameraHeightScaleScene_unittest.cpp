// Metric scale from camera_height on a rendered scene: keygrid-sim's
// room_loop and office_loop scenes (config/sim) are rendered at their keyframes' ground-truth
// poses, map points are taken where the rendered depth puts the scene's surfaces (one per 8 x 8
// pixel cell of a 160 x 120 view with the Kinect's field of view, as a feature grid spreads
// them), given the noise of bundle-adjusted monocular points, and the map is scaled by an
// unknown factor and moved. The scale recovered from the scene's camera height must be within
// the 2 %.
//
// Substitute for a monocular run: the poses are ground truth and the points' noise is a model
// (below), not the output of the monocular tracker, which does not exist yet.
#include <keygrid/sfm/CameraHeightScale.h>
#include <keygrid/sim/Renderer.h>
#include <keygrid/sim/Scene.h>

#include <TestData.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <random>
#include <string>

using namespace keygrid;
using mrpt::poses::CPose3D;

namespace camera_height_scale_scene_unittest
{
namespace
{
/** Depth std of a map point [m]: z^2 sigma_px / (f B) for 1 px of keypoint noise at the
 * Kinect's f = 525 px, with B = 0.5 m the effective baseline of a point refined by local bundle
 * adjustment over the keyframes that see it (a wall point of room_loop stays in view over
 * about 1 m of the camera's circle; a floor point of office_loop over a few metres of forward
 * motion, at 20 .. 30 deg from it); across the ray z sigma_px / f. */
constexpr double kPixelStd = 1.0, kFocal = 525.0, kBaseline = 0.5;
/** Share of gross outliers (a wrong match triangulated at 0.7 .. 1.3 times the true depth). */
constexpr double kOutlierShare = 0.01;
/** The target. */
constexpr double kScaleTolerance = 0.02;

struct SceneCase
{
	const char* file;
	unsigned keyframeEvery;  //!< frames between keyframes
};

void PrintTo(const SceneCase& c, std::ostream* os) { *os << c.file; }

class CameraHeightScaleScene : public ::testing::TestWithParam<SceneCase>
{
};

/** The height of the scene's camera above its floor: every waypoint's eye at one height, every
 * "floor*" quad at one height [m]. */
double configuredCameraHeight(const sim::Scene& scene)
{
	const auto& wps = scene.trajectory.waypoints();
	EXPECT_FALSE(wps.empty());
	for (const auto& w : wps) EXPECT_EQ(w.eye.z(), wps.front().eye.z()) << "the camera is not at one height";
	double floorZ = 0;
	int floors = 0;
	for (const auto& o : scene.objects)
		if (o.name.rfind("floor", 0) == 0)
		{
			if (floors++ == 0) floorZ = o.T_world_obj.translation().z();
			EXPECT_EQ(o.T_world_obj.translation().z(), floorZ) << o.name;
		}
	EXPECT_GT(floors, 0) << "no floor object";
	return wps.front().eye.z() - floorZ;
}
}  // namespace

TEST_P(CameraHeightScaleScene, RecoversTheMetricScaleFromTheCameraHeight)
{
	sim::Scene scene = sim::Scene::loadFromFile(test::sourceDir() + "/config/sim/" + GetParam().file);
	const double cameraHeight = configuredCameraHeight(scene);
	// A quarter of the Kinect's resolution, same field of view.
	scene.camera.width = 160;
	scene.camera.height = 120;
	scene.camera.fx = scene.camera.fy = kFocal / 4;
	scene.camera.cx = 79.5;
	scene.camera.cy = 59.5;
	const sim::Renderer renderer(scene);
	const auto K = scene.camera.pinhole();

	// The unknown map: p_map = k (Q p + t).
	const double k = 0.29;
	const Eigen::Matrix3d Q = Eigen::AngleAxisd(2.4, Eigen::Vector3d(-0.2, 0.9, 0.4).normalized()).toRotationMatrix();
	const Eigen::Vector3d t(-3.0, 11.0, 0.5);

	std::mt19937 rng(3);
	std::uniform_real_distribution<double> U01(0, 1);
	std::normal_distribution<double> N(0, 1);
	std::vector<CPose3D> T_map_cam;
	std::vector<Eigen::Vector3d> points_map;
	sim::RenderOutput view;
	constexpr int kCell = 8;
	for (std::size_t i = 0; i < scene.options.frames; i += GetParam().keyframeEvery)
	{
		const CPose3D T_world_cam = scene.cameraPose(i);
		const Eigen::Isometry3d T_wc = sim::Renderer::toIsometry(T_world_cam);
		renderer.render(T_wc, scene.frameTime(i), view);
		for (int v0 = 0; v0 + kCell <= view.depth.rows; v0 += kCell)
			for (int u0 = 0; u0 + kCell <= view.depth.cols; u0 += kCell)
			{
				const int u = u0 + static_cast<int>(U01(rng) * kCell), v = v0 + static_cast<int>(U01(rng) * kCell);
				double z = view.depth.at<float>(v, u);
				if (!(z > 0)) continue;
				// Noise along the ray (depth) and across it (pixel), in the camera frame.
				if (U01(rng) < kOutlierShare) z *= 0.7 + 0.6 * U01(rng);
				else z += N(rng) * z * z * kPixelStd / (kFocal * kBaseline);
				const double across = z * kPixelStd / kFocal;
				const Eigen::Vector3d ray((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
				const Eigen::Vector3d p_cam = z * ray + across * Eigen::Vector3d(N(rng), N(rng), 0);
				points_map.push_back(k * (Q * (T_wc * p_cam) + t));
			}
		const Eigen::Vector3d c_map = k * (Q * T_wc.translation() + t);
		const Eigen::Matrix3d R_map_cam = Q * T_wc.linear();
		mrpt::math::CMatrixDouble33 R;
		mrpt::math::CVectorFixedDouble<3> tm;
		for (int a = 0; a < 3; a++)
		{
			tm[a] = c_map[a];
			for (int b = 0; b < 3; b++) R(a, b) = R_map_cam(a, b);
		}
		T_map_cam.push_back(CPose3D::FromRotationAndTranslation(R, tm));
	}

	sfm::CameraHeightScaleOptions opts;
	opts.cameraHeight = cameraHeight;
	const auto r = sfm::CameraHeightScaleEstimator(opts).estimate(T_map_cam, points_map);
	ASSERT_TRUE(r.ok) << r.message;
	const double err = r.scale * k - 1;
	std::cout << GetParam().file << ": " << T_map_cam.size() << " keyframes, " << points_map.size() << " points, camera height "
			  << cameraHeight << " m: scale error " << 100 * err << " %, " << r.message << "\n";
	EXPECT_LT(std::abs(err), kScaleTolerance);
	// The floor's normal is the world's up: a tilt of 1 deg would move the floor under a camera
	// 1 m from the floor points' centroid by 1.7 cm, 1.3 % of the camera's height.
	EXPECT_GT(r.floorNormal.dot(Q * Eigen::Vector3d::UnitZ()), std::cos(1.0 * M_PI / 180.0));
	// The simulator's cameras have no roll: every x axis is horizontal, so the turn axis is the
	// world's up (to rounding), and both loops turn the camera all the way round: the turn is
	// the arc the keyframes' headings cover, the circle less its largest gap, which office_loop's
	// keyframes (50 frames apart) leave at their fastest turn (72 deg).
	EXPECT_LT((r.turnAxis - Q * Eigen::Vector3d::UnitZ()).norm(), 1e-9);
	EXPECT_GT(r.turnDeg, 270.0);
	EXPECT_LT(r.floorToTurnAxisDeg, 1.0);
}

INSTANTIATE_TEST_SUITE_P(
	SimScenes, CameraHeightScaleScene, ::testing::Values(SceneCase{"room_loop.ini", 15}, SceneCase{"office_loop.ini", 50}),
	[](const ::testing::TestParamInfo<SceneCase>& info) { return std::string(info.param.file).substr(0, std::string(info.param.file).find('.')); });
}  // namespace camera_height_scale_scene_unittest
