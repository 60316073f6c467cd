#pragma once
/** \file DepthOfScan.h
 * Depth image [m] and camera of an MRPT 3D range scan, shared by the map plugins.
 */
#include <keygrid/core/RgbdCamera.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <opencv2/core.hpp>

#include <cmath>

namespace keygrid::detail
{
/** Range image converted to depth along the optical axis (also when the scan stores Euclidean
 * ranges); false when the scan has no range image. */
inline bool depthOfScan(const mrpt::obs::CObservation3DRangeScan& o, cv::Mat& depth, core::RgbdCamera& cam)
{
	o.load();
	if (!o.hasRangeImage || o.rangeImage.rows() == 0) return false;
	cam = core::RgbdCamera::FromTCamera(o.cameraParams, o.rangeUnits);
	const int rows = static_cast<int>(o.rangeImage.rows()), cols = static_cast<int>(o.rangeImage.cols());
	cam.width = static_cast<unsigned>(cols);
	cam.height = static_cast<unsigned>(rows);
	depth.create(rows, cols, CV_32FC1);
	const core::PinholeIntrinsics K = cam.pinhole();
	for (int r = 0; r < rows; ++r)
	{
		float* d = depth.ptr<float>(r);
		for (int c = 0; c < cols; ++c)
		{
			float z = o.rangeImage(r, c) * o.rangeUnits;
			if (!o.range_is_depth && z > 0)
			{
				const double xn = K.rayX(c), yn = K.rayY(r);
				z = static_cast<float>(z / std::sqrt(1.0 + xn * xn + yn * yn));
			}
			d[c] = z;
		}
	}
	return true;
}
}  // namespace keygrid::detail
