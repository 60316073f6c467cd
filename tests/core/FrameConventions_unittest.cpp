// The optical ("cam") <-> MRPT depth-frame conversion, checked against MRPT's own definitions.
#include <keygrid/core/FrameConventions.h>
#include <keygrid/core/RgbdObservation.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include "TestData.h"

using namespace keygrid::core;

TEST(FrameConventions, AxesMapAsDocumented)
{
	const auto p = camToMrptDepth({1.0, 2.0, 3.0});  // right, down, forward
	EXPECT_EQ(p.x, 3.0);   // forward
	EXPECT_EQ(p.y, -1.0);  // left = -right
	EXPECT_EQ(p.z, -2.0);  // up = -down
	const auto q = mrptDepthToCam(p);
	EXPECT_EQ(q.x, 1.0);
	EXPECT_EQ(q.y, 2.0);
	EXPECT_EQ(q.z, 3.0);
}

TEST(FrameConventions, PoseMatchesMrptCoincidentCameraPose)
{
	// MRPT's default relativePoseIntensityWRTDepth is the optical frame for coinciding cameras.
	const mrpt::obs::CObservation3DRangeScan obs;
	const auto& a = T_depth_cam();
	const auto& b = obs.relativePoseIntensityWRTDepth;
	EXPECT_NEAR((a.getHomogeneousMatrixVal<mrpt::math::CMatrixDouble44>() -
				 b.getHomogeneousMatrixVal<mrpt::math::CMatrixDouble44>())
					.array()
					.abs()
					.maxCoeff(),
				0.0, 1e-12);
	// Composing a point with the pose equals the axis permutation.
	for (const auto& pc : {mrpt::math::TPoint3D(0.3, -0.2, 1.7), mrpt::math::TPoint3D(-1, 4, 0.5)})
	{
		const auto viaPose = a.composePoint(pc);
		const auto viaAxes = camToMrptDepth(pc);
		EXPECT_NEAR(viaPose.x, viaAxes.x, 1e-15);
		EXPECT_NEAR(viaPose.y, viaAxes.y, 1e-15);
		EXPECT_NEAR(viaPose.z, viaAxes.z, 1e-15);
	}
}

TEST(FrameConventions, SensorAndCameraPosesRoundTrip)
{
	const mrpt::poses::CPose3D T_world_cam(1.0, -2.0, 0.5, 0.3, -0.2, 0.1);
	const auto T_world_depth = sensorPoseFromCameraPose(T_world_cam);
	const auto back = cameraPoseFromSensorPose(T_world_depth);
	EXPECT_NEAR((back.asVectorVal() - T_world_cam.asVectorVal()).norm(), 0.0, 1e-12);
	// The camera looks along its optical +z, which is the sensor's +X.
	const auto ahead_cam = T_world_cam.composePoint(mrpt::math::TPoint3D(0, 0, 1));
	const auto ahead_depth = T_world_depth.composePoint(mrpt::math::TPoint3D(1, 0, 0));
	EXPECT_NEAR((ahead_cam - ahead_depth).norm(), 0.0, 1e-12);
}

TEST(FrameConventions, MrptUnprojectionAgreesWithOpticalBackProjection)
{
	// A frame written by keygrid, unprojected by MRPT, lands where the optical pinhole model says.
	Frame f;
	f.camera = RgbdCamera::Preset("fr3");  // no distortion: MRPT unprojects with K only
	f.camera.width = 64;
	f.camera.height = 48;
	f.camera.cx = 31.5;
	f.camera.cy = 23.5;
	f.grey = cv::Mat(48, 64, CV_8UC1, cv::Scalar(100));
	f.depthRaw = cv::Mat(48, 64, CV_16UC1);
	for (int r = 0; r < 48; r++)
		for (int c = 0; c < 64; c++) f.depthRaw.at<uint16_t>(r, c) = static_cast<uint16_t>(5000 + 37 * r + 11 * c);
	auto obs = makeRgbdObservation(f);
	mrpt::maps::CSimplePointsMap pts;
	mrpt::obs::T3DPointsProjectionParams pp;
	pp.takeIntoAccountSensorPoseOnRobot = true;
	obs->unprojectInto(pts, pp);
	ASSERT_EQ(pts.size(), 64u * 48u);
	std::size_t k = 0;
	for (int r = 0; r < 48; r++)
		for (int c = 0; c < 64; c++, k++)
		{
			const double z = f.depthRaw.at<uint16_t>(r, c) * double(f.camera.depthUnits);
			const mrpt::math::TPoint3D p_cam((c - f.camera.cx) / f.camera.fx * z, (r - f.camera.cy) / f.camera.fy * z, z);
			const auto expect = camToMrptDepth(p_cam);
			float x, y, zz;
			pts.getPoint(k, x, y, zz);
			ASSERT_NEAR(x, expect.x, 1e-4) << r << "," << c;
			ASSERT_NEAR(y, expect.y, 1e-4) << r << "," << c;
			ASSERT_NEAR(zz, expect.z, 1e-4) << r << "," << c;
		}
}
