#pragma once
/** \file DepthRegistration.h
 * Re-projects a depth image from the depth camera into the intensity (colour) camera, for
 * observations whose cameras do not coincide (raw Kinect / OpenNI2 without hardware registration).
 */
#include <mrpt/img/TCamera.h>
#include <mrpt/poses/CPose3D.h>
#include <opencv2/core/mat.hpp>

namespace keygrid::core
{
/** Returns the raw depth (CV_16UC1, same units as the input) seen from the intensity camera.
 *
 * Each valid depth pixel (u, v, d) is lifted to p_d = d * ray_d(u, v) in the depth camera's
 * optical frame (ray_d from the undistorted pixel, z = 1), expressed in the MRPT depth frame,
 * moved into the intensity camera's optical frame with T_depth_intensity^-1, projected with the
 * intensity intrinsics and distortion, and written with a z-buffer (nearest surface wins).
 * `T_depth_intensity` is CObservation3DRangeScan::relativePoseIntensityWRTDepth. */
cv::Mat registerDepthToIntensity(
	const cv::Mat& depthRaw, float units, const mrpt::img::TCamera& depthCam,
	const mrpt::img::TCamera& intensityCam, const mrpt::poses::CPose3D& T_depth_intensity);

/** Projects a point given in a camera's optical frame through pinhole + plumb-bob distortion.
 * Returns false for points behind the camera. */
bool projectWithDistortion(
	const mrpt::img::TCamera& cam, double x, double y, double z, double& u, double& v);

}  // namespace keygrid::core
