// The one back-projection (PinholeIntrinsics.h): projecting its point gives the pixel back,
// its point is the pixel's ray scaled by the depth to the last bit (what loops that precompute
// rays rely on), and RgbdCamera::pinhole() carries the camera's four numbers.
#include <keygrid/core/PinholeIntrinsics.h>
#include <keygrid/core/RgbdCamera.h>

#include "TestData.h"

using namespace keygrid;

TEST(PinholeIntrinsics, BackProjectedPointsProjectToTheirPixel)
{
	const core::PinholeIntrinsics K = core::RgbdCamera::Preset("fr1").pinhole();
	for (double u : {0.0, 17.25, 318.6, 639.0})
		for (double v : {0.0, 255.3, 479.0})
			for (double d : {0.4, 2.0, 7.9})
			{
				const Eigen::Vector3d p = K.backProject(u, v, d);
				EXPECT_EQ(p.z(), d);
				EXPECT_NEAR(K.fx * p.x() / p.z() + K.cx, u, 1e-12);
				EXPECT_NEAR(K.fy * p.y() / p.z() + K.cy, v, 1e-12);
				// The ray scaled by the depth: the same operations, the same bits.
				const Eigen::Vector3d r = K.ray(u, v);
				EXPECT_EQ(r.z(), 1.0);
				EXPECT_EQ(r.x() * d, p.x());
				EXPECT_EQ(r.y() * d, p.y());
			}
}

TEST(PinholeIntrinsics, CameraConversionAndFloatCopyKeepTheValues)
{
	const auto cam = core::RgbdCamera::Preset("fr1");
	const core::PinholeIntrinsics K = cam.pinhole();
	EXPECT_EQ(K.fx, cam.fx);
	EXPECT_EQ(K.fy, cam.fy);
	EXPECT_EQ(K.cx, cam.cx);
	EXPECT_EQ(K.cy, cam.cy);
	// In float, the arithmetic is float's: (u - cx) / fx rounded at each step.
	const auto Kf = K.cast<float>();
	EXPECT_EQ(Kf.fx, static_cast<float>(cam.fx));
	EXPECT_EQ(Kf.cy, static_cast<float>(cam.cy));
	const float u = 100.f, cx = static_cast<float>(cam.cx), fx = static_cast<float>(cam.fx);
	EXPECT_EQ(Kf.rayX(u), (u - cx) / fx);
}
