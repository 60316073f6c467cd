#include <keygrid/maps/OccupancyGridMetrics.h>

#include <cmath>

namespace keygrid::maps
{
FloorPlanGrid::Cell FloorPlanGrid::at(double x, double y) const
{
	return cell(
		static_cast<int>(std::floor((x - xMin) / resolution)),
		static_cast<int>(std::floor((y - yMin) / resolution)));
}

OccupancyMetrics evaluateOccupancy(
	const CISMOccupancyGrid2D& est, const FloorPlanGrid& gt, const OccupancyMetricsOptions& opts)
{
	OccupancyMetrics m;
	const double tol = opts.matchTolerance;
	const double tol2 = tol * tol + 1e-12;

	// Any cell of `state` in `grid` within tol of (x, y)? Checks cell centres.
	auto estHasOccupiedNear = [&](double x, double y) {
		const int r = static_cast<int>(std::ceil(tol / est.resolution()));
		const int cx = est.x2idx(x), cy = est.y2idx(y);
		for (int dy = -r; dy <= r; dy++)
			for (int dx = -r; dx <= r; dx++)
			{
				const double ex = est.idx2x(cx + dx) - x, ey = est.idx2y(cy + dy) - y;
				if (ex * ex + ey * ey <= tol2 + 0.5 * est.resolution() * est.resolution() &&
					est.cellState(cx + dx, cy + dy) == CellState::Occupied)
					return true;
			}
		return false;
	};
	auto gtHasOccupiedNear = [&](double x, double y) {
		const int r = static_cast<int>(std::ceil(tol / gt.resolution));
		const int cx = static_cast<int>(std::floor((x - gt.xMin) / gt.resolution));
		const int cy = static_cast<int>(std::floor((y - gt.yMin) / gt.resolution));
		for (int dy = -r; dy <= r; dy++)
			for (int dx = -r; dx <= r; dx++)
			{
				const double gx = gt.xMin + (cx + dx + 0.5) * gt.resolution - x;
				const double gy = gt.yMin + (cy + dy + 0.5) * gt.resolution - y;
				if (gx * gx + gy * gy <= tol2 + 0.5 * gt.resolution * gt.resolution &&
					gt.cell(cx + dx, cy + dy) == FloorPlanGrid::Occupied)
					return true;
			}
		return false;
	};

	// Precision side and free precision: iterate the estimate.
	for (int cy = 0; cy < est.sizeY(); cy++)
		for (int cx = 0; cx < est.sizeX(); cx++)
		{
			const double x = est.idx2x(cx), y = est.idx2y(cy);
			const auto g = gt.at(x, y);
			if (g == FloorPlanGrid::Ignore) continue;
			const CellState s = est.cellState(cx, cy);
			if (s == CellState::Occupied)
			{
				m.estOccupied++;
				if (gtHasOccupiedNear(x, y)) m.estOccupiedMatched++;
			}
			else if (s == CellState::Free)
			{
				m.estFree++;
				if (g == FloorPlanGrid::Free) m.estFreeCorrect++;
			}
		}
	// Recall side and free accuracy: iterate the ground truth.
	for (int cy = 0; cy < gt.sizeY; cy++)
		for (int cx = 0; cx < gt.sizeX; cx++)
		{
			const auto g = gt.cell(cx, cy);
			const double x = gt.xMin + (cx + 0.5) * gt.resolution;
			const double y = gt.yMin + (cy + 0.5) * gt.resolution;
			if (g == FloorPlanGrid::Occupied)
			{
				m.gtOccupied++;
				if (estHasOccupiedNear(x, y)) m.gtOccupiedMatched++;
			}
			else if (g == FloorPlanGrid::Free)
			{
				const CellState s = est.stateAt(x, y);
				if (s == CellState::Unknown) continue;
				m.gtFreeObserved++;
				if (s == CellState::Free) m.gtFreeCorrect++;
			}
		}
	auto ratio = [](size_t a, size_t b) { return b ? static_cast<double>(a) / static_cast<double>(b) : 0.0; };
	m.precision = ratio(m.estOccupiedMatched, m.estOccupied);
	m.recall = ratio(m.gtOccupiedMatched, m.gtOccupied);
	m.f1 = (m.precision + m.recall) > 0 ? 2 * m.precision * m.recall / (m.precision + m.recall) : 0.0;
	m.freeAccuracy = ratio(m.gtFreeCorrect, m.gtFreeObserved);
	m.freePrecision = ratio(m.estFreeCorrect, m.estFree);
	return m;
}

}  // namespace keygrid::maps
