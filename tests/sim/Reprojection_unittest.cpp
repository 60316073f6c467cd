// Geometry consistency: every pixel's depth, back-projected with the ground-truth pose and the
// intrinsics, lands on the surface of the object the renderer says it hit -- both straight
// from the renderer and through the rawlog observation with MRPT's own unprojection.
#include <keygrid/core/FrameConventions.h>
#include <keygrid/core/RgbdObservation.h>
#include <keygrid/sim/Simulator.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/T3DPointsProjectionParams.h>
#include <opencv2/calib3d.hpp>

#include "SimTestScenes.h"
#include "TestData.h"

#include <cmath>

using namespace keygrid;

namespace
{
std::string sceneIni()
{
	return "[scene]\nseed = 2\nframes = 2\n" + test::tinyCameraIni() +
		   "[sensor]\nnoise = false\nmax_incidence_deg = 90\nmax_range = 10\n"
		   "[trajectory]\nwp_00 = 0.3 0.2 1.4  3 1.1 0.6\nwp_01 = 0.5 0.6 1.3  3 1.9 0.7\n"
		   "[object.floor]\ntype = quad\ncorner = -5 -6 0\nedge1 = 9 0 0\nedge2 = 0 14 0\n"
		   "[object.wall]\ntype = quad\ncorner = 4 -6 0\nedge1 = 0 14 0\nedge2 = 0 0 5\n"
		   "[object.box]\ntype = box\ncentre = 2.5 0.9 0.5\nsize = 0.6 0.8 1.0\nyaw = 31\npitch = "
		   "5\n"
		   "[object.drum]\ntype = cylinder\ncentre = 2.2 2.0 0.6\nradius = 0.3\nheight = 1.2\nroll "
		   "= 4\n";
}

/** Distance from local point p to the surface of `s` (exact for these shapes). */
double surfaceDistance(const sim::Shape& s, const Eigen::Vector3d& p)
{
	const Eigen::Vector3d& h = s.half;
	switch (s.type)
	{
		case sim::ShapeType::Quad:
		{
			const double dx = std::max(0.0, std::abs(p.x()) - h.x()),
						 dy = std::max(0.0, std::abs(p.y()) - h.y());
			return std::sqrt(p.z() * p.z() + dx * dx + dy * dy);
		}
		case sim::ShapeType::Box:
		{
			const Eigen::Vector3d q = p.cwiseAbs() - h;
			const double outside = q.cwiseMax(0.0).norm();
			return outside > 0 ? outside : -q.maxCoeff();
		}
		case sim::ShapeType::Cylinder:
		{
			const double dr = std::hypot(p.x(), p.y()) - h.x(), dz = std::abs(p.z()) - h.z();
			if (dr > 0 || dz > 0) return std::hypot(std::max(dr, 0.0), std::max(dz, 0.0));
			return std::min(-dr, -dz);
		}
	}
	return 1e9;
}
}  // namespace

TEST(Reprojection, BackProjectedPixelsLieOnTheHitSurface)
{
	const sim::Scene scene = test::sceneFromString(sceneIni());
	const sim::Simulator simulator(scene, 2);
	sim::SimFrame f;
	for (std::size_t i = 0; i < 2; i++)
	{
		simulator.frame(i, f);
		const Eigen::Isometry3d T_wc = sim::Renderer::toIsometry(f.T_world_cam);
		int hits = 0, seen[4] = {0, 0, 0, 0};
		for (int v = 0; v < 120; v++)
			for (int u = 0; u < 160; u++)
			{
				const int idx = f.render.objectIndex.at<int>(v, u);
				if (idx < 0) continue;
				const double z = f.render.depth.at<float>(v, u);
				const Eigen::Vector3d p_cam(z * (u - 79.5) / 131.25, z * (v - 59.5) / 131.25, z);
				const auto& obj = scene.objects[idx];
				const Eigen::Vector3d p_obj =
					obj.poseAt(scene.frameTime(i)).inverse() * (T_wc * p_cam);
				ASSERT_LT(surfaceDistance(obj.shape, p_obj), 2e-6 * z)
					<< obj.name << " at " << u << "," << v;
				hits++;
				seen[idx]++;
			}
		EXPECT_EQ(hits, 160 * 120) << "the floor and wall fill the background";
		for (int k = 0; k < 4; k++) EXPECT_GT(seen[k], 50) << scene.objects[k].name;
	}
}

TEST(Reprojection, MrptUnprojectionOfTheObservationMatchesTheScene)
{
	const sim::Scene scene = test::sceneFromString(sceneIni());
	const sim::Simulator simulator(scene, 2);
	sim::SimFrame f;
	simulator.frame(1, f);
	auto obs = core::makeRgbdObservation(f.frame);
	// Where MRPT puts the sensor: the pose of its depth frame (x forward, z up) in the world.
	obs->sensorPose = core::sensorPoseFromCameraPose(f.T_world_cam);
	mrpt::maps::CSimplePointsMap pts;
	mrpt::obs::T3DPointsProjectionParams pp;
	pp.takeIntoAccountSensorPoseOnRobot = true;
	obs->unprojectInto(pts, pp);
	ASSERT_GT(pts.size(), 160u * 120 * 9 / 10);
	std::size_t far = 0;
	for (std::size_t k = 0; k < pts.size(); k++)
	{
		const Eigen::Vector3d p(
			pts.getPointsBufferRef_x()[k], pts.getPointsBufferRef_y()[k],
			pts.getPointsBufferRef_z()[k]);
		double best = 1e9;
		for (const auto& o : scene.objects)
			best = std::min(best, std::abs(surfaceDistance(o.shape, o.T_world_obj.inverse() * p)));
		// Raw depth steps of 0.2 mm move a point by <= 0.1 mm * |ray| / z along its ray.
		far += best > 3e-4;
	}
	EXPECT_EQ(far, 0u);
}

TEST(Reprojection, DistortedCameraRaysFollowTheLensModel)
{
	// TUM fr1 distortion on a quarter-size camera: the renderer casts undistorted rays.
	std::string ini = sceneIni();
	ini.replace(
		ini.find("[camera]"), std::string("[camera]").size(),
		"[camera]\nk1 = 0.262383\nk2 = -0.953104\np1 = -0.005358\np2 = 0.002628\nk3 = 1.163314");
	const sim::Scene scene = test::sceneFromString(ini);
	ASSERT_TRUE(scene.camera.hasDistortion());
	const sim::Simulator simulator(scene, 2);
	sim::SimFrame f;
	simulator.frame(0, f);
	const Eigen::Isometry3d T_wc = sim::Renderer::toIsometry(f.T_world_cam);
	const cv::Matx33d K(131.25, 0, 79.5, 0, 131.25, 59.5, 0, 0, 1);
	const std::vector<double> dist(scene.camera.dist.begin(), scene.camera.dist.end());
	std::vector<cv::Point2d> px, norm;
	for (int v = 0; v < 120; v += 7)
		for (int u = 0; u < 160; u += 7) px.emplace_back(u, v);
	cv::undistortPoints(px, norm, K, dist);
	std::vector<cv::Point3d> pts;
	for (std::size_t k = 0; k < px.size(); k++)
	{
		const int u = static_cast<int>(px[k].x), v = static_cast<int>(px[k].y);
		const int idx = f.render.objectIndex.at<int>(v, u);
		ASSERT_GE(idx, 0);
		const double z = f.render.depth.at<float>(v, u);
		const Eigen::Vector3d p_cam(z * norm[k].x, z * norm[k].y, z);
		const auto& obj = scene.objects[idx];
		EXPECT_LT(
			std::abs(surfaceDistance(obj.shape, obj.T_world_obj.inverse() * (T_wc * p_cam))),
			2e-6 * z);
		pts.emplace_back(p_cam.x(), p_cam.y(), p_cam.z());
	}
	// The forward lens model (OpenCV projectPoints) maps the 3D points back to their pixels.
	std::vector<cv::Point2d> back;
	cv::projectPoints(pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, dist, back);
	for (std::size_t k = 0; k < px.size(); k++) EXPECT_LT(cv::norm(back[k] - px[k]), 0.01) << px[k];
}
