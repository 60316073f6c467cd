#pragma once
/** \file Dda.h
 * 3D digital differential analyser (Amanatides & Woo, "A Fast Voxel Traversal Algorithm for
 * Ray Tracing", Eurographics 1987) on a regular grid of cubic voxels of edge `resolution`,
 * voxel (i,j,k) = [i*res, (i+1)*res) x ... (see VoxelBlockGrid.h).
 *
 * Parametrise the segment as p(t) = a + t (b - a), t in [0, 1], in voxel units. Along axis x the
 * ray crosses a voxel boundary every tDeltaX = 1 / |b.x - a.x| in t; the first crossing is at
 * tMaxX = (next boundary - a.x) / (b.x - a.x). Each step advances the axis with the smallest
 * tMax, so voxels are visited in order of increasing t. The number of steps per axis is fixed
 * in advance (|end - start| voxel indices): an axis whose steps are used up is never stepped
 * again, so the traversal ends exactly in the voxel of b despite rounding. Ties (measure zero
 * for real data) step y before x and z before the other two.
 */
#include <keygrid/maps/VoxelBlockGrid.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <vector>

namespace keygrid
{
/** Calls visit(const VoxelIndex&) for every voxel the segment a -> b [m] passes through, from
 * the voxel of a to the voxel of b inclusive, in traversal order. The visitor returns true to
 * continue, false to stop early. Returns the number of voxels visited. */
template <class Visitor>
inline std::size_t traverseSegment(
	const mrpt::math::TPoint3D& a, const mrpt::math::TPoint3D& b, double resolution,
	Visitor&& visit)
{
	const double inv = 1.0 / resolution;
	const double a_v[3] = {a.x * inv, a.y * inv, a.z * inv};
	const double b_v[3] = {b.x * inv, b.y * inv, b.z * inv};

	int32_t cur[3], step[3], remaining[3];
	double tMax[3], tDelta[3];
	constexpr double kInf = std::numeric_limits<double>::infinity();
	for (int k = 0; k < 3; ++k)
	{
		cur[k] = floorToInt(a_v[k]);
		const int32_t end = floorToInt(b_v[k]);
		const double d = b_v[k] - a_v[k];
		remaining[k] = std::abs(end - cur[k]);
		if (remaining[k] == 0 || d == 0.0)
		{
			step[k] = 0;
			remaining[k] = 0;
			tMax[k] = kInf;
			tDelta[k] = kInf;
			continue;
		}
		step[k] = d > 0 ? 1 : -1;
		tDelta[k] = std::abs(1.0 / d);
		const double boundary = d > 0 ? cur[k] + 1.0 : static_cast<double>(cur[k]);
		tMax[k] = (boundary - a_v[k]) / d;
	}

	// Scalars and plain branches rather than arrays indexed by the selected axis, which are
	// several times slower in this inner loop. An exhausted axis has tMax = inf, so the smallest tMax always belongs to an
	// axis with steps left while the total is positive.
	int32_t x = cur[0], y = cur[1], z = cur[2];
	double tx = tMax[0], ty = tMax[1], tz = tMax[2];
	int32_t rx = remaining[0], ry = remaining[1], rz = remaining[2];
	std::size_t visited = 1;
	if (!visit(VoxelIndex{x, y, z})) return visited;
	for (int32_t total = rx + ry + rz; total > 0; --total)
	{
		if (tx < ty)
		{
			if (tx < tz)
			{
				x += step[0];
				tx = --rx > 0 ? tx + tDelta[0] : kInf;
			}
			else
			{
				z += step[2];
				tz = --rz > 0 ? tz + tDelta[2] : kInf;
			}
		}
		else if (ty < tz)
		{
			y += step[1];
			ty = --ry > 0 ? ty + tDelta[1] : kInf;
		}
		else
		{
			z += step[2];
			tz = --rz > 0 ? tz + tDelta[2] : kInf;
		}
		++visited;
		if (!visit(VoxelIndex{x, y, z})) break;
	}
	return visited;
}

/** Convenience: the voxels of traverseSegment() as a vector (tests, tools). */
inline std::vector<VoxelIndex> voxelsAlongSegment(
	const mrpt::math::TPoint3D& a, const mrpt::math::TPoint3D& b, double resolution)
{
	std::vector<VoxelIndex> out;
	traverseSegment(a, b, resolution, [&](const VoxelIndex& v) {
		out.push_back(v);
		return true;
	});
	return out;
}

}  // namespace keygrid
