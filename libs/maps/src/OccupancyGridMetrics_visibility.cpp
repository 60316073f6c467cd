/** \file OccupancyGridMetrics_visibility.cpp
 * What of a floor plan a set of noise-free depth images shows (markSeenCells): the visibility
 * mask behind the "seen" metrics of OccupancyGridMetrics.h. */
#include <keygrid/maps/Dda.h>
#include <keygrid/maps/OccupancyGridMetrics.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace keygrid::maps
{
bool FloorPlanVisibilityOptions::isValid(std::string* error) const
{
	std::string why;
	if (!(zMin <= zMax)) why = "zMin must be <= zMax (got " + std::to_string(zMin) + ", " + std::to_string(zMax) + ")";
	else if (!(maxRange > 0)) why = "maxRange must be > 0 m (got " + std::to_string(maxRange) + ")";
	else if (!(floorTolerance >= 0)) why = "floorTolerance must be >= 0 m (got " + std::to_string(floorTolerance) + ")";
	else if (freeRayStride < 1) why = "freeRayStride must be >= 1 (got " + std::to_string(freeRayStride) + ")";
	if (error) *error = why;
	return why.empty();
}

namespace
{
class SeenMarker
{
   public:
	SeenMarker(FloorPlanGrid& gt, const FloorPlanVisibilityOptions& o) : m_gt(gt), m_o(o) {}

	int cellX(double x) const { return static_cast<int>(std::floor((x - m_gt.xMin) / m_gt.resolution)); }
	int cellY(double y) const { return static_cast<int>(std::floor((y - m_gt.yMin) / m_gt.resolution)); }
	void mark(int cx, int cy, uint8_t bit)
	{
		if (cx >= 0 && cy >= 0 && cx < m_gt.sizeX && cy < m_gt.sizeY)
			m_gt.seen[static_cast<size_t>(cx) + static_cast<size_t>(cy) * m_gt.sizeX] |= bit;
	}

	/** A surface point p inside the band and range: its cell, both cells within 1 mm of a boundary. */
	void surface(const mrpt::math::TPoint3D& p)
	{
		for (const double ex : {-1e-3, 1e-3})
			for (const double ey : {-1e-3, 1e-3}) mark(cellX(p.x + ex), cellY(p.y + ey), FloorPlanGrid::SeenSurface);
	}

	/** The ray c -> p: the cells its part inside the band crosses (within maxRange), except the
	 * cell of p; a floor point's own cell too. */
	void freeSpace(const mrpt::math::TPoint3D& c, const mrpt::math::TPoint3D& p)
	{
		const double dz = p.z - c.z;
		double t0 = 0, t1 = 1;
		if (std::abs(dz) < 1e-12)
		{
			if (c.z < m_o.zMin || c.z > m_o.zMax) t1 = -1;
		}
		else
		{
			const double ta = (m_o.zMin - c.z) / dz, tb = (m_o.zMax - c.z) / dz;
			t0 = std::max(0.0, std::min(ta, tb));
			t1 = std::min(1.0, std::max(ta, tb));
		}
		const double h = std::hypot(p.x - c.x, p.y - c.y);
		if (h > 0) t1 = std::min(t1, m_o.maxRange / h);
		const int pcx = cellX(p.x), pcy = cellY(p.y);
		const bool floor = std::abs(p.z) <= m_o.floorTolerance;
		if (t0 < t1)
		{
			// 2D traversal as a 3D one in the plan's cell units, at constant height inside cell z = 0.
			const double half = 0.5 * m_gt.resolution;
			const mrpt::math::TPoint3D a(
				c.x + t0 * (p.x - c.x) - m_gt.xMin, c.y + t0 * (p.y - c.y) - m_gt.yMin, half);
			const mrpt::math::TPoint3D b(
				c.x + t1 * (p.x - c.x) - m_gt.xMin, c.y + t1 * (p.y - c.y) - m_gt.yMin, half);
			traverseSegment(a, b, m_gt.resolution, [&](const VoxelIndex& v) {
				if (floor || v.x != pcx || v.y != pcy) mark(v.x, v.y, FloorPlanGrid::SeenFreeSpace);
				return true;
			});
		}
		if (floor && h <= m_o.maxRange) mark(pcx, pcy, static_cast<uint8_t>(FloorPlanGrid::SeenFreeSpace | FloorPlanGrid::SeenFloor));
		// The ray's part below the band: the floor-level space of the cells it crosses.
		double f0 = 0, f1 = 1;
		if (std::abs(dz) < 1e-12)
		{
			if (c.z >= m_o.zMin) f1 = -1;
		}
		else if (dz < 0)
			f0 = std::max(0.0, (m_o.zMin - c.z) / dz);
		else
			f1 = std::min(1.0, (m_o.zMin - c.z) / dz);
		if (h > 0) f1 = std::min(f1, m_o.maxRange / h);
		if (f0 < f1)
		{
			const double half = 0.5 * m_gt.resolution;
			const mrpt::math::TPoint3D a(c.x + f0 * (p.x - c.x) - m_gt.xMin, c.y + f0 * (p.y - c.y) - m_gt.yMin, half);
			const mrpt::math::TPoint3D b(c.x + f1 * (p.x - c.x) - m_gt.xMin, c.y + f1 * (p.y - c.y) - m_gt.yMin, half);
			traverseSegment(a, b, m_gt.resolution, [&](const VoxelIndex& v) {
				if (floor || v.x != pcx || v.y != pcy) mark(v.x, v.y, FloorPlanGrid::SeenFloor);
				return true;
			});
		}
	}

   private:
	FloorPlanGrid& m_gt;
	const FloorPlanVisibilityOptions& m_o;
};
}  // namespace

void markSeenCells(
	FloorPlanGrid& gt, const cv::Mat& depth, const core::RgbdCamera& cam, const mrpt::poses::CPose3D& T_floor_cam,
	const FloorPlanVisibilityOptions& opts)
{
	std::string why;
	if (!opts.isValid(&why)) throw std::invalid_argument("FloorPlanVisibilityOptions: " + why);
	if (depth.type() != CV_32FC1)
		throw std::invalid_argument("markSeenCells: depth image must be CV_32FC1 (metres), got type " + std::to_string(depth.type()));
	if (depth.cols != static_cast<int>(cam.width) || depth.rows != static_cast<int>(cam.height))
		throw std::invalid_argument("markSeenCells: depth image is " + std::to_string(depth.cols) + " x " +
			std::to_string(depth.rows) + ", the camera " + std::to_string(cam.width) + " x " + std::to_string(cam.height));
	if (gt.seen.empty()) gt.seen.assign(gt.cells.size(), 0);
	if (gt.seen.size() != gt.cells.size())
		throw std::invalid_argument("FloorPlanGrid::seen has " + std::to_string(gt.seen.size()) + " cells, the plan " +
			std::to_string(gt.cells.size()));
	SeenMarker marker(gt, opts);
	const mrpt::math::TPoint3D c(T_floor_cam.x(), T_floor_cam.y(), T_floor_cam.z());
	const core::PinholeIntrinsics K = cam.pinhole();
	for (int v = 0; v < depth.rows; v++)
	{
		const float* row = depth.ptr<float>(v);
		for (int u = 0; u < depth.cols; u++)
		{
			const double d = row[u];
			if (!(d > 0)) continue;
			const Eigen::Vector3d p_cam = K.backProject(u, v, d);
			mrpt::math::TPoint3D p;
			T_floor_cam.composePoint(p_cam.x(), p_cam.y(), p_cam.z(), p.x, p.y, p.z);
			if (p.z >= opts.zMin && p.z <= opts.zMax && std::hypot(p.x - c.x, p.y - c.y) <= opts.maxRange)
				marker.surface(p);
			if (u % opts.freeRayStride == 0 && v % opts.freeRayStride == 0) marker.freeSpace(c, p);
		}
	}
}

}  // namespace keygrid::maps
