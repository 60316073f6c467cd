#include <keygrid/maps/GridRayTraversal.h>

#include <algorithm>

namespace keygrid::maps
{
std::vector<GridCellVisit> bresenhamCells(int x0, int y0, int x1, int y1)
{
	std::vector<GridCellVisit> out;
	out.reserve(static_cast<size_t>(std::max(std::abs(x1 - x0), std::abs(y1 - y0))) + 1);
	bresenhamLine(x0, y0, x1, y1, [&](int cx, int cy) { out.push_back({cx, cy, 1.0f}); });
	return out;
}

std::vector<GridCellVisit> wuCells(double x0, double y0, double x1, double y1)
{
	std::vector<GridCellVisit> out;
	wuLine(x0, y0, x1, y1, [&](int cx, int cy, float w, double, double) {
		out.push_back({cx, cy, w});
	});
	return out;
}

}  // namespace keygrid::maps
