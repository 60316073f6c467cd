#pragma once
/** \file ISMSimEvaluation.h
 * Helpers shared by the keygrid-sim accuracy test of CISMOccupancyGrid2D and the benchmark
 * tool tests/benchmarks/maps_ism/ism2d_sim_eval.cpp: the simulator's floor plan as the metric's
 * ground truth, and the sparse input (3D points from the depth at ORB keypoints).
 */
#include <keygrid/core/Frame.h>
#include <keygrid/maps/OccupancyGridMetrics.h>
#include <keygrid/sim/GroundTruthOccupancy.h>
#include <mrpt/math/TPoint3D.h>
#include <mrpt/poses/CPose3D.h>

#include <opencv2/features2d.hpp>

#include <cmath>
#include <cstdint>
#include <vector>

namespace keygrid::test
{
/** keygrid-sim's floor plan (world frame: z up, floor z = 0) as the metric's ground truth;
 * every cell is scored (the plan covers the room). */
inline maps::FloorPlanGrid toFloorPlanGrid(const sim::FloorPlan& fp)
{
	return maps::FloorPlanGrid::fromOccupancy(fp.resolution, fp.origin.x(), fp.origin.y(), fp.width, fp.height, fp.occupied);
}

/** Sparse keyframe input standing in for SLAM map points: ORB keypoints of the grey image,
 * back-projected with the measured depth at the (rounded) keypoint, in world coordinates. */
inline std::vector<mrpt::math::TPoint3D> keypointPoints(
	const core::Frame& f, const mrpt::poses::CPose3D& T_world_cam, cv::Ptr<cv::ORB>& orb)
{
	std::vector<cv::KeyPoint> kps;
	orb->detect(f.grey, kps);
	std::vector<mrpt::math::TPoint3D> pts;
	const auto& c = f.camera;
	for (const auto& kp : kps)
	{
		const int u = static_cast<int>(std::lround(kp.pt.x)), v = static_cast<int>(std::lround(kp.pt.y));
		if (u < 0 || v < 0 || u >= f.depth.cols || v >= f.depth.rows) continue;
		const float d = f.depth.at<float>(v, u);
		if (!(d > 0)) continue;
		const double xc = (kp.pt.x - c.cx) / c.fx * d, yc = (kp.pt.y - c.cy) / c.fy * d;
		double wx, wy, wz;
		T_world_cam.composePoint(xc, yc, d, wx, wy, wz);
		pts.emplace_back(wx, wy, wz);
	}
	return pts;
}

/** Ground truth restricted to what the cameras could see: a GT-occupied cell stays scored only
 * if a point of the noise-free rendered depth (`perfectDepth`, one per keyframe) lies in it (or
 * within 1 mm of it: surfaces on cell boundaries) inside the height band [zMin, zMax] and within
 * `maxRange` horizontally of the camera; other GT-occupied cells become Ignore. Call once per
 * keyframe on `visible` (same lattice as the plan, initially all 0), then restrictToVisible(). */
inline void markVisibleCells(
	std::vector<uint8_t>& visible, const maps::FloorPlanGrid& gt, const cv::Mat& perfectDepth,
	const core::RgbdCamera& cam, const mrpt::poses::CPose3D& T_world_cam, double zMin, double zMax,
	double maxRange)
{
	visible.resize(gt.cells.size(), 0);
	for (int v = 0; v < perfectDepth.rows; v++)
		for (int u = 0; u < perfectDepth.cols; u++)
		{
			const float d = perfectDepth.at<float>(v, u);
			if (!(d > 0)) continue;
			double x, y, z;
			T_world_cam.composePoint((u - cam.cx) / cam.fx * d, (v - cam.cy) / cam.fy * d, d, x, y, z);
			if (z < zMin || z > zMax || std::hypot(x - T_world_cam.x(), y - T_world_cam.y()) > maxRange) continue;
			for (const double ex : {-1e-3, 1e-3})
				for (const double ey : {-1e-3, 1e-3})
				{
					const int cx = static_cast<int>(std::floor((x + ex - gt.xMin) / gt.resolution));
					const int cy = static_cast<int>(std::floor((y + ey - gt.yMin) / gt.resolution));
					if (cx >= 0 && cy >= 0 && cx < gt.sizeX && cy < gt.sizeY)
						visible[static_cast<size_t>(cx) + static_cast<size_t>(cy) * gt.sizeX] = 1;
				}
		}
}

inline maps::FloorPlanGrid restrictToVisible(maps::FloorPlanGrid gt, const std::vector<uint8_t>& visible)
{
	for (size_t i = 0; i < gt.cells.size(); i++)
		if (gt.cells[i] == maps::FloorPlanGrid::Occupied && !(i < visible.size() && visible[i]))
			gt.cells[i] = maps::FloorPlanGrid::Ignore;
	return gt;
}

}  // namespace keygrid::test
