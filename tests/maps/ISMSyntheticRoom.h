#pragma once
/** \file ISMSyntheticRoom.h
 * A synthetic rectangular room for the ISM grid tests: walls at x = +-hx, y = +-hy (placed on
 * 5 cm cell centres), floor z = 0, ceiling z = 2.5, expressed in a "level" frame that can be
 * tilted into the world by T_world_level. Generates sparse keyframe points (random wall/floor
 * samples in the field of view) and dense depth images by ray casting, plus the floor plan.
 */
#include <keygrid/core/FrameConventions.h>
#include <keygrid/maps/OccupancyGridMetrics.h>
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

#include "CameraPoses.h"

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace keygrid::test
{
struct SyntheticRoom
{
	double hx{2.025}, hy{1.525}, height{2.5};
	mrpt::poses::CPose3D T_world_level;  ///< the room's level frame in the world
	/** Solid axis-aligned boxes in the level frame (furniture: a table top, its legs, a crate). */
	struct Box
	{
		mrpt::math::TPoint3D lo, hi;
		bool containsXY(double x, double y) const { return x >= lo.x && x <= hi.x && y >= lo.y && y <= hi.y; }
	};
	std::vector<Box> boxes;

	/** Optical camera at (x, y, h) in the level frame, yaw theta, pitched down by `pitch`. */
	mrpt::poses::CPose3D cameraPose(double x, double y, double h, double yaw, double pitch) const
	{
		return T_world_level + levelOpticalPose(x, y, h, yaw, pitch);
	}

	/** Depth along the optical axis of the first surface hit by the ray through normalised
	 * image coordinates (xn, yn), or 0 beyond maxDepth. */
	double castDepth(const mrpt::poses::CPose3D& T_world_cam, double xn, double yn, double maxDepth) const
	{
		const mrpt::poses::CPose3D T_level_cam = T_world_cam - T_world_level;
		const auto d = T_level_cam.rotateVector(mrpt::math::TVector3D(xn, yn, 1.0));
		const auto o = T_level_cam.translation();
		double best = std::numeric_limits<double>::max();
		auto plane = [&](double oc, double dc, double c) {
			if (std::abs(dc) < 1e-12) return;
			const double t = (c - oc) / dc;
			if (t > 1e-9 && t < best) best = t;
		};
		plane(o.x, d.x, hx);
		plane(o.x, d.x, -hx);
		plane(o.y, d.y, hy);
		plane(o.y, d.y, -hy);
		plane(o.z, d.z, 0.0);
		plane(o.z, d.z, height);
		for (const Box& b : boxes)
		{
			// Slab test: the entry parameter of the ray into the box, if it enters in front.
			double t0 = 0, t1 = std::numeric_limits<double>::max();
			for (int i = 0; i < 3; i++)
			{
				const double oi = i == 0 ? o.x : i == 1 ? o.y : o.z, di = d[i];
				const double lo = i == 0 ? b.lo.x : i == 1 ? b.lo.y : b.lo.z, hi = i == 0 ? b.hi.x : i == 1 ? b.hi.y : b.hi.z;
				if (std::abs(di) < 1e-12)
				{
					if (oi < lo || oi > hi) t0 = t1 + 1;
					continue;
				}
				double ta = (lo - oi) / di, tb = (hi - oi) / di;
				if (ta > tb) std::swap(ta, tb);
				t0 = std::max(t0, ta);
				t1 = std::min(t1, tb);
			}
			if (t0 <= t1 && t0 > 1e-9 && t0 < best) best = t0;
		}
		return best <= maxDepth ? best : 0.0;  // d has unit optical z: t is the depth
	}

	/** Dense depth image (MRPT observation, sensorPose identity) of a camera. */
	mrpt::obs::CObservation3DRangeScan renderDepth(
		const mrpt::poses::CPose3D& T_world_cam, int w, int h, double f, double maxDepth = 6.0) const
	{
		mrpt::obs::CObservation3DRangeScan obs;
		obs.hasRangeImage = true;
		obs.range_is_depth = true;
		obs.rangeUnits = 0.001f;
		obs.rangeImage.resize(h, w);
		obs.cameraParams.ncols = static_cast<uint32_t>(w);
		obs.cameraParams.nrows = static_cast<uint32_t>(h);
		obs.cameraParams.fx(f);
		obs.cameraParams.fy(f);
		obs.cameraParams.cx(0.5 * (w - 1));
		obs.cameraParams.cy(0.5 * (h - 1));
		obs.cameraParamsIntensity = obs.cameraParams;
		for (int r = 0; r < h; r++)
			for (int c = 0; c < w; c++)
			{
				const double z = castDepth(T_world_cam, (c - 0.5 * (w - 1)) / f, (r - 0.5 * (h - 1)) / f, maxDepth);
				obs.rangeImage(r, c) = static_cast<uint16_t>(std::lround(z / 0.001));
			}
		return obs;
	}

	/** Sparse "map points" seen by a camera: random wall and floor samples (world frame) inside
	 * a 58 x 45 degree field of view, up to maxDepth, with normal noise of sigma. */
	std::vector<mrpt::math::TPoint3D> samplePoints(
		const mrpt::poses::CPose3D& T_world_cam, size_t count, double sigma, std::mt19937& rng,
		double maxDepth = 4.5) const
	{
		std::uniform_real_distribution<double> U(-1.0, 1.0);
		std::normal_distribution<double> N(0.0, sigma);
		const double tx = std::tan(29.0 * M_PI / 180), ty = std::tan(22.5 * M_PI / 180);
		std::vector<mrpt::math::TPoint3D> out;
		for (size_t tries = 0; out.size() < count && tries < 50 * count; tries++)
		{
			const double xn = tx * U(rng), yn = ty * U(rng);
			const double z = castDepth(T_world_cam, xn, yn, maxDepth);
			if (z <= 0) continue;
			const double zn = z + N(rng);
			out.push_back(T_world_cam.composePoint(mrpt::math::TPoint3D(xn * zn, yn * zn, zn)));
		}
		return out;
	}

	/** Ground-truth floor plan in the level frame at `res` (walls occupied, inside free). */
	maps::FloorPlanGrid floorPlan(double res = 0.05) const
	{
		maps::FloorPlanGrid g;
		g.resolution = res;
		g.xMin = -hx - 0.475;
		g.yMin = -hy - 0.475;
		g.sizeX = static_cast<int>(std::lround((2 * hx + 0.95) / res));
		g.sizeY = static_cast<int>(std::lround((2 * hy + 0.95) / res));
		g.cells.assign(static_cast<size_t>(g.sizeX) * g.sizeY, maps::FloorPlanGrid::Ignore);
		for (int cy = 0; cy < g.sizeY; cy++)
			for (int cx = 0; cx < g.sizeX; cx++)
			{
				const double x = g.xMin + (cx + 0.5) * res, y = g.yMin + (cy + 0.5) * res;
				const double ax = std::abs(x), ay = std::abs(y);
				auto& c = g.cells[static_cast<size_t>(cx) + static_cast<size_t>(cy) * g.sizeX];
				const double e = 0.25 * res;
				if ((std::abs(ax - hx) < e && ay < hy + e) || (std::abs(ay - hy) < e && ax < hx + e))
					c = maps::FloorPlanGrid::Occupied;
				else if (ax < hx && ay < hy)
					c = maps::FloorPlanGrid::Free;
			}
		return g;
	}
};

}  // namespace keygrid::test
