#pragma once
/** \file GridRayTraversal.h
 * Ray traversal over a 2D grid, the two variants the ISM grid can use:
 * - bresenhamLine(): Bresenham's integer line, one 8-connected cell per step of the major axis;
 * - wuLine(): Xiaolin Wu's anti-aliased line (the idea of the "modified Bresenham" patent the
 *   paper cites, Levine 1998): per step of the major axis the two cells straddling the exact
 *   line, weighted by their distance to it (weights sum to one).
 *
 * Coordinates are "cell coordinates": cell (i, j) has its centre at (i, j). The visitors are
 * templates so that the inner loop of the map inlines them.
 */
#include <cmath>
#include <cstdlib>
#include <utility>
#include <vector>

namespace keygrid::maps
{
/** Visits every cell of Bresenham's line from (x0, y0) to (x1, y1), both included, in order.
 * visit(int cx, int cy). */
template <class Visitor>
inline void bresenhamLine(int x0, int y0, int x1, int y1, Visitor&& visit)
{
	const int dx = std::abs(x1 - x0);
	const int dy = -std::abs(y1 - y0);
	const int sx = x0 < x1 ? 1 : -1;
	const int sy = y0 < y1 ? 1 : -1;
	int err = dx + dy;  // error of the next candidate, scaled by 2 below
	for (;;)
	{
		visit(x0, y0);
		if (x0 == x1 && y0 == y1) break;
		const int e2 = 2 * err;
		if (e2 >= dy)
		{
			err += dy;
			x0 += sx;
		}
		if (e2 <= dx)
		{
			err += dx;
			y0 += sy;
		}
	}
}

/** Xiaolin Wu's anti-aliased line between two continuous points (cell coordinates).
 * For every integer position i of the major axis between round(start) and round(end) it visits
 * the two cells below/above the exact line: visit(int cx, int cy, float weight, double px,
 * double py), where (px, py) is the exact point of the line at that step (so the caller can
 * compute the distance along the ray). Cells with zero weight are skipped. */
template <class Visitor>
inline void wuLine(double x0, double y0, double x1, double y1, Visitor&& visit)
{
	const bool steep = std::abs(y1 - y0) > std::abs(x1 - x0);
	if (steep)
	{
		std::swap(x0, y0);
		std::swap(x1, y1);
	}
	const double dx = x1 - x0;
	const double gradient = (dx == 0.0) ? 0.0 : (y1 - y0) / dx;
	const int i0 = static_cast<int>(std::lround(x0));
	const int i1 = static_cast<int>(std::lround(x1));
	const int step = i0 <= i1 ? 1 : -1;
	for (int i = i0;; i += step)
	{
		const double y = y0 + gradient * (i - x0);
		const double fy = std::floor(y);
		const int j = static_cast<int>(fy);
		const float wUpper = static_cast<float>(y - fy);  // weight of cell j + 1
		const float wLower = 1.0f - wUpper;
		const double px = steep ? y : i;
		const double py = steep ? i : y;
		if (wLower > 0.0f)
		{
			if (steep) visit(j, i, wLower, px, py);
			else
				visit(i, j, wLower, px, py);
		}
		if (wUpper > 0.0f)
		{
			if (steep) visit(j + 1, i, wUpper, px, py);
			else
				visit(i, j + 1, wUpper, px, py);
		}
		if (i == i1) break;
	}
}

/** One visited cell, for tests and callers that want a list. */
struct GridCellVisit
{
	int cx{0}, cy{0};
	float weight{1.0f};
};

/** Bresenham's line as a list (convenience over bresenhamLine()). */
std::vector<GridCellVisit> bresenhamCells(int x0, int y0, int x1, int y1);
/** Wu's anti-aliased line as a list (convenience over wuLine()). */
std::vector<GridCellVisit> wuCells(double x0, double y0, double x1, double y1);

}  // namespace keygrid::maps
