#pragma once
/** \file Grid3DTestScenes.h
 * Synthetic depth images for the 3D grid tests, rendered analytically (ray / plane and
 * ray / box intersections), so the expected voxels follow from closed forms; and the small
 * submapped grid of a wall that the conflict, morphing and I/O tests start from.
 */
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <mrpt/poses/CPose3D.h>
#include <opencv2/core/mat.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace keygrid::test
{
/** A small undistorted pinhole camera (64x48, f = 60 px): ~56 x 44 degrees like a Kinect. */
inline core::RgbdCamera smallCamera(unsigned w = 64, unsigned h = 48, double f = 60.0)
{
	core::RgbdCamera c;
	c.name = "test";
	c.width = w;
	c.height = h;
	c.fx = c.fy = f;
	c.cx = (w - 1) / 2.0;
	c.cy = (h - 1) / 2.0;
	return c;
}

/** Depth of a fronto-parallel wall at distance `z` [m] in front of the camera. */
inline cv::Mat wallDepth(const core::RgbdCamera& c, float z)
{
	return cv::Mat(static_cast<int>(c.height), static_cast<int>(c.width), CV_32FC1, cv::Scalar(z));
}

/** Depth image of the inside of an axis-aligned box room [lo, hi] (world), seen from
 * T_world_cam (optical frame). Pixels are traced through their centres. */
inline cv::Mat boxRoomDepth(const core::RgbdCamera& c, const mrpt::poses::CPose3D& T_world_cam,
	const mrpt::math::TPoint3D& lo, const mrpt::math::TPoint3D& hi)
{
	cv::Mat d(static_cast<int>(c.height), static_cast<int>(c.width), CV_32FC1, cv::Scalar(0.0f));
	const auto R = T_world_cam.getRotationMatrix();
	const double o[3] = {T_world_cam.x(), T_world_cam.y(), T_world_cam.z()};
	const double l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
	for (unsigned v = 0; v < c.height; ++v)
		for (unsigned u = 0; u < c.width; ++u)
		{
			const double pc[3] = {(u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0};  // z = 1
			double dir[3];
			for (int k = 0; k < 3; ++k) dir[k] = R(k, 0) * pc[0] + R(k, 1) * pc[1] + R(k, 2) * pc[2];
			// Exit distance (in units of depth, since pc.z = 1) through the box walls.
			double tExit = std::numeric_limits<double>::infinity();
			for (int k = 0; k < 3; ++k)
			{
				if (dir[k] > 1e-12) tExit = std::min(tExit, (h[k] - o[k]) / dir[k]);
				else if (dir[k] < -1e-12) tExit = std::min(tExit, (l[k] - o[k]) / dir[k]);
			}
			d.at<float>(static_cast<int>(v), static_cast<int>(u)) = static_cast<float>(tExit);
		}
	return d;
}

/** A 5 cm submapped grid that opens a submap on a conflict of 100 voxels, changed by
 * `configure(map)`, then given two keyframes (ids 1, 2; travelled 0 and 0.1 m) at the origin
 * of a wall 2.02 m ahead (smallCamera): with the default options its voxels become confidently
 * occupied (2 hits = 1.7 >= 1.5). */
template <class Configure>
CSubmappedOccupancyGrid3D mapOfWall(Configure&& configure)
{
	CSubmappedOccupancyGrid3D m(0.05);
	m.insertionOptions.conflict.conflictMinVoxels = 100;
	configure(m);
	const auto cam = smallCamera();
	m.insertDepthFrame(wallDepth(cam, 2.02f), cam, mrpt::poses::CPose3D(), 0.0, 1);
	m.insertDepthFrame(wallDepth(cam, 2.02f), cam, mrpt::poses::CPose3D(), 0.1, 2);
	return m;
}

/** mapOfWall with the default options. */
inline CSubmappedOccupancyGrid3D mapOfWall()
{
	return mapOfWall([](CSubmappedOccupancyGrid3D&) {});
}

}  // namespace keygrid::test
