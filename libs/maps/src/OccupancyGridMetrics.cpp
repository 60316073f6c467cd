#include <keygrid/maps/ExportFrame.h>
#include <keygrid/maps/OccupancyGridMetrics.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>

namespace keygrid::maps
{
FloorPlanGrid FloorPlanGrid::fromOccupancy(
	double resolution, double xMin, double yMin, int sizeX, int sizeY, const std::vector<uint8_t>& occupied)
{
	if (sizeX < 0 || sizeY < 0 || occupied.size() != static_cast<std::size_t>(sizeX) * static_cast<std::size_t>(sizeY))
		throw std::invalid_argument(
			"FloorPlanGrid::fromOccupancy: " + std::to_string(occupied.size()) + " cells for a " + std::to_string(sizeX) +
			" x " + std::to_string(sizeY) + " lattice");
	FloorPlanGrid g;
	static_cast<GridLattice&>(g) = GridLattice{resolution, xMin, yMin, sizeX, sizeY};
	g.cells.resize(occupied.size());
	for (std::size_t i = 0; i < occupied.size(); i++) g.cells[i] = occupied[i] ? Occupied : Free;
	return g;
}

FloorPlanGrid::Cell FloorPlanGrid::at(double x, double y) const
{
	return cell(
		static_cast<int>(std::floor((x - xMin) / resolution)),
		static_cast<int>(std::floor((y - yMin) / resolution)));
}

bool FloorPlanGrid::inView(int cx, int cy) const
{
	if (seen.empty()) return true;
	const Cell c = cell(cx, cy);
	if (c == Ignore) return false;
	const uint8_t bit = c == Occupied ? SeenSurface : SeenFreeSpace;
	return (seen[cellIndex(cx, cy)] & bit) != 0;
}

bool FloorPlanGrid::floorInView(int cx, int cy) const
{
	if (seen.empty()) return true;
	if (cell(cx, cy) == Ignore) return false;
	return (seen[cellIndex(cx, cy)] & SeenFloor) != 0;
}

bool OccupancyMetricsOptions::isValid(std::string* error) const
{
	std::string why;
	if (!(matchTolerance >= 0)) why = "matchTolerance must be >= 0 m (got " + std::to_string(matchTolerance) + ")";
	else if (hazardMarginCells < 0)
		why = "hazardMarginCells must be >= 0 (got " + std::to_string(hazardMarginCells) + ")";
	if (error) *error = why;
	return why.empty();
}

const char* cellVerdictName(CellVerdict v)
{
	switch (v)
	{
		case CellVerdict::Unknown: return "unknown";
		case CellVerdict::Free: return "free";
		case CellVerdict::Occupied: return "occupied";
		case CellVerdict::Missed: return "missed";
		case CellVerdict::MissedUnseen: return "missed, never in view";
		case CellVerdict::EdgeCalledFree: return "obstacle edge called free";
		case CellVerdict::Hazard: return "hazard";
		case CellVerdict::FalseObstacle: return "false obstacle";
	}
	return "?";
}

namespace
{
/** Uniform read access to a CISMOccupancyGrid2D or a TriStateGrid for the scoring below. */
struct EstView
{
	double res, xMin, yMin;
	int sizeX, sizeY;
	std::function<CellState(int, int)> state;

	double resolution() const { return res; }
	int x2idx(double x) const { return static_cast<int>(std::floor((x - xMin) / res)); }
	int y2idx(double y) const { return static_cast<int>(std::floor((y - yMin) / res)); }
	double idx2x(int cx) const { return xMin + (cx + 0.5) * res; }
	double idx2y(int cy) const { return yMin + (cy + 0.5) * res; }
	CellState cellState(int cx, int cy) const { return state(cx, cy); }
	CellState stateAt(double x, double y) const { return state(x2idx(x), y2idx(y)); }
};

EstView viewOf(const TriStateGrid& est)
{
	return EstView{est.resolution, est.xMin, est.yMin, est.sizeX, est.sizeY,
		[&est](int cx, int cy) { return est.cell(cx, cy); }};
}

/** The neighbourhood queries and the per-cell verdict shared by the metrics and the overlay. */
class Scorer
{
   public:
	Scorer(const EstView& est, const FloorPlanGrid& gt, const OccupancyMetricsOptions& opts)
		: m_est(est), m_gt(gt), m_opts(opts), m_tol2(opts.matchTolerance * opts.matchTolerance + 1e-12)
	{
		std::string why;
		if (!opts.isValid(&why)) throw std::invalid_argument("OccupancyMetricsOptions: " + why);
		if (!gt.seen.empty() && gt.seen.size() != gt.cells.size())
			throw std::invalid_argument(
				"FloorPlanGrid::seen has " + std::to_string(gt.seen.size()) + " cells, the plan " +
				std::to_string(gt.cells.size()));
	}

	/** Any estimated occupied cell whose centre lies within tolerance of (x, y)? */
	bool estHasOccupiedNear(double x, double y) const
	{
		const double res = m_est.resolution();
		const int r = static_cast<int>(std::ceil(m_opts.matchTolerance / res));
		const int cx = m_est.x2idx(x), cy = m_est.y2idx(y);
		for (int dy = -r; dy <= r; dy++)
			for (int dx = -r; dx <= r; dx++)
			{
				const double ex = m_est.idx2x(cx + dx) - x, ey = m_est.idx2y(cy + dy) - y;
				if (ex * ex + ey * ey <= m_tol2 + 0.5 * res * res &&
					m_est.cellState(cx + dx, cy + dy) == CellState::Occupied)
					return true;
			}
		return false;
	}
	/** Any GT-occupied cell whose centre lies within tolerance of (x, y)? */
	bool gtHasOccupiedNear(double x, double y) const
	{
		const double res = m_gt.resolution;
		const int r = static_cast<int>(std::ceil(m_opts.matchTolerance / res));
		const int cx = static_cast<int>(std::floor((x - m_gt.xMin) / res));
		const int cy = static_cast<int>(std::floor((y - m_gt.yMin) / res));
		for (int dy = -r; dy <= r; dy++)
			for (int dx = -r; dx <= r; dx++)
			{
				const double gx = m_gt.xMin + (cx + dx + 0.5) * res - x;
				const double gy = m_gt.yMin + (cy + dy + 0.5) * res - y;
				if (gx * gx + gy * gy <= m_tol2 + 0.5 * res * res &&
					m_gt.cell(cx + dx, cy + dy) == FloorPlanGrid::Occupied)
					return true;
			}
		return false;
	}
	/** Any GT-free cell within Chebyshev distance r of GT cell (cx, cy)? */
	bool gtFreeWithin(int cx, int cy, int r) const
	{
		for (int dy = -r; dy <= r; dy++)
			for (int dx = -r; dx <= r; dx++)
				if (m_gt.cell(cx + dx, cy + dy) == FloorPlanGrid::Free) return true;
		return false;
	}
	double centreX(int cx) const { return m_gt.xMin + (cx + 0.5) * m_gt.resolution; }
	double centreY(int cy) const { return m_gt.yMin + (cy + 0.5) * m_gt.resolution; }

	CellVerdict verdict(int cx, int cy) const
	{
		const auto g = m_gt.cell(cx, cy);
		if (g == FloorPlanGrid::Ignore) return CellVerdict::Unknown;
		const double x = centreX(cx), y = centreY(cy);
		const CellState s = m_est.stateAt(x, y);
		if (g == FloorPlanGrid::Occupied)
		{
			if (s == CellState::Free)
				return gtFreeWithin(cx, cy, m_opts.hazardMarginCells) ? CellVerdict::EdgeCalledFree : CellVerdict::Hazard;
			if (estHasOccupiedNear(x, y)) return CellVerdict::Occupied;
			return m_gt.inView(cx, cy) ? CellVerdict::Missed : CellVerdict::MissedUnseen;
		}
		if (s == CellState::Free) return CellVerdict::Free;
		if (s == CellState::Occupied) return gtHasOccupiedNear(x, y) ? CellVerdict::Occupied : CellVerdict::FalseObstacle;
		return CellVerdict::Unknown;
	}

   private:
	const EstView& m_est;
	const FloorPlanGrid& m_gt;
	const OccupancyMetricsOptions& m_opts;
	const double m_tol2;
};

OccupancyMetrics evaluate(const EstView& est, const FloorPlanGrid& gt, const OccupancyMetricsOptions& opts)
{
	const Scorer sc(est, gt, opts);
	OccupancyMetrics m;

	// Precision side and free precision: iterate the estimate.
	for (int cy = 0; cy < est.sizeY; cy++)
		for (int cx = 0; cx < est.sizeX; cx++)
		{
			const double x = est.idx2x(cx), y = est.idx2y(cy);
			const auto g = gt.at(x, y);
			if (g == FloorPlanGrid::Ignore) continue;
			const CellState s = est.cellState(cx, cy);
			if (s == CellState::Occupied)
			{
				m.estOccupied++;
				if (sc.gtHasOccupiedNear(x, y)) m.estOccupiedMatched++;
			}
			else if (s == CellState::Free)
			{
				m.estFree++;
				if (g == FloorPlanGrid::Free) m.estFreeCorrect++;
			}
		}
	// Recall side, free accuracy and the navigation metrics: iterate the ground truth.
	for (int cy = 0; cy < gt.sizeY; cy++)
		for (int cx = 0; cx < gt.sizeX; cx++)
		{
			const auto g = gt.cell(cx, cy);
			const double x = sc.centreX(cx), y = sc.centreY(cy);
			const CellState s = est.stateAt(x, y);
			if (g == FloorPlanGrid::Occupied)
			{
				m.gtOccupied++;
				const bool matched = sc.estHasOccupiedNear(x, y);
				if (matched) m.gtOccupiedMatched++;
				if (s == CellState::Free) m.gtOccupiedCalledFree++;
				if (!sc.gtFreeWithin(cx, cy, opts.hazardMarginCells))
				{
					m.gtOccupiedInterior++;
					if (s == CellState::Free) m.hazardCells++;
				}
				if (sc.gtFreeWithin(cx, cy, 1) && gt.inView(cx, cy))
				{
					m.gtBoundarySeen++;
					if (matched) m.gtBoundarySeenMatched++;
				}
			}
			else if (g == FloorPlanGrid::Free)
			{
				if (gt.inView(cx, cy))
				{
					m.gtFreeSeen++;
					if (s == CellState::Free) m.gtFreeSeenCalledFree++;
				}
				if (gt.floorInView(cx, cy))
				{
					m.gtFreeFloorSeen++;
					if (s == CellState::Free) m.gtFreeFloorSeenCalledFree++;
				}
				if (s == CellState::Unknown) continue;
				m.gtFreeObserved++;
				if (s == CellState::Free) m.gtFreeCorrect++;
				if (sc.gtHasOccupiedNear(x, y))
				{
					m.gtFreeObservedNearOccupied++;
					if (s == CellState::Free) m.gtFreeCorrectNearOccupied++;
				}
			}
		}
	auto ratio = [](size_t a, size_t b) { return b ? static_cast<double>(a) / static_cast<double>(b) : 0.0; };
	auto harmonic = [](double p, double r) { return (p + r) > 0 ? 2 * p * r / (p + r) : 0.0; };
	m.precision = ratio(m.estOccupiedMatched, m.estOccupied);
	m.recall = ratio(m.gtOccupiedMatched, m.gtOccupied);
	m.f1 = harmonic(m.precision, m.recall);
	m.freeAccuracy = ratio(m.gtFreeCorrect, m.gtFreeObserved);
	m.freeAccuracyAwayFromOccupied = ratio(
		m.gtFreeCorrect - m.gtFreeCorrectNearOccupied, m.gtFreeObserved - m.gtFreeObservedNearOccupied);
	m.freePrecision = ratio(m.estFreeCorrect, m.estFree);
	m.boundaryRecall = ratio(m.gtBoundarySeenMatched, m.gtBoundarySeen);
	m.freeRecall = ratio(m.gtFreeSeenCalledFree, m.gtFreeSeen);
	m.freeF1 = harmonic(m.freePrecision, m.freeRecall);
	m.freeRecallFloorSeen = ratio(m.gtFreeFloorSeenCalledFree, m.gtFreeFloorSeen);
	m.freeF1FloorSeen = harmonic(m.freePrecision, m.freeRecallFloorSeen);
	return m;
}
}  // namespace

OccupancyMetrics evaluateOccupancy(
	const TriStateGrid& est, const FloorPlanGrid& gt, const OccupancyMetricsOptions& opts)
{
	return evaluate(viewOf(est), gt, opts);
}

OccupancyMetrics evaluateOccupancy(
	const CISMOccupancyGrid2D& est, const FloorPlanGrid& gt, const OccupancyMetricsOptions& opts)
{
	return evaluate(
		EstView{est.resolution(), est.xMin(), est.yMin(), est.sizeX(), est.sizeY(),
			[&](int cx, int cy) { return est.cellState(cx, cy); }},
		gt, opts);
}

std::vector<CellVerdict> classifyCells(const TriStateGrid& est, const FloorPlanGrid& gt, const OccupancyMetricsOptions& opts)
{
	const EstView view = viewOf(est);
	const Scorer sc(view, gt, opts);
	std::vector<CellVerdict> v(gt.numCells());
	for (int cy = 0; cy < gt.sizeY; cy++)
		for (int cx = 0; cx < gt.sizeX; cx++)
			v[gt.cellIndex(cx, cy)] = sc.verdict(cx, cy);
	return v;
}

TriStateGrid TriStateGrid::fromGrid(const CISMOccupancyGrid2D& g)
{
	TriStateGrid t;
	t.resolution = g.resolution();
	t.xMin = g.xMin();
	t.yMin = g.yMin();
	t.sizeX = g.sizeX();
	t.sizeY = g.sizeY();
	t.cells.resize(t.numCells());
	for (int cy = 0; cy < t.sizeY; cy++)
		for (int cx = 0; cx < t.sizeX; cx++)
			t.cells[t.cellIndex(cx, cy)] = g.cellState(cx, cy);
	return t;
}

TriStateGrid TriStateGrid::loadRosMapServer(const std::string& yamlPath)
{
	std::ifstream yaml(yamlPath);
	if (!yaml) throw std::runtime_error("cannot read '" + yamlPath + "'");
	TriStateGrid t;
	std::string image, line;
	bool haveRes = false, haveOrigin = false;
	while (std::getline(yaml, line))
	{
		if (line.rfind("image:", 0) == 0)
		{
			std::istringstream is(line.substr(6));
			is >> image;
		}
		else if (line.rfind("resolution:", 0) == 0)
			haveRes = static_cast<bool>(std::istringstream(line.substr(11)) >> t.resolution);
		else if (line.rfind("# keygrid T_world_floor", 0) == 0)
		{
			if (auto T = floorFrameFromComment(line)) t.T_world_floor = T;
		}
		else if (line.rfind("origin:", 0) == 0)
		{
			std::string v = line.substr(7);
			for (char& c : v)
				if (c == '[' || c == ']' || c == ',') c = ' ';
			haveOrigin = static_cast<bool>(std::istringstream(v) >> t.xMin >> t.yMin);
		}
	}
	if (image.empty() || !haveRes || !haveOrigin || !(t.resolution > 0))
		throw std::runtime_error("'" + yamlPath + "': missing image, resolution or origin");
	const auto slash = yamlPath.find_last_of('/');
	const std::string pgmPath =
		(image[0] == '/' || slash == std::string::npos) ? image : yamlPath.substr(0, slash + 1) + image;
	std::ifstream pgm(pgmPath, std::ios::binary);
	if (!pgm) throw std::runtime_error("cannot read '" + pgmPath + "'");
	// P5 header with optional comment lines.
	auto token = [&]() {
		std::string tok;
		while (pgm >> tok)
		{
			if (tok[0] != '#') return tok;
			std::getline(pgm, line);
		}
		throw std::runtime_error("'" + pgmPath + "': truncated header");
	};
	if (token() != "P5") throw std::runtime_error("'" + pgmPath + "': not a binary PGM (P5)");
	t.sizeX = std::stoi(token());
	t.sizeY = std::stoi(token());
	if (std::stoi(token()) != 255) throw std::runtime_error("'" + pgmPath + "': maxval must be 255");
	pgm.get();  // the single whitespace after maxval
	std::vector<unsigned char> img(t.numCells());
	pgm.read(reinterpret_cast<char*>(img.data()), static_cast<std::streamsize>(img.size()));
	if (!pgm) throw std::runtime_error("'" + pgmPath + "': truncated pixel data");
	t.cells.resize(img.size());
	for (int r = 0; r < t.sizeY; r++)
	{
		const int cy = t.sizeY - 1 - r;  // image row 0 = largest y
		for (int cx = 0; cx < t.sizeX; cx++)
		{
			const unsigned char v = img[static_cast<size_t>(r) * t.sizeX + cx];
			t.cells[t.cellIndex(cx, cy)] =
				v == 0 ? CellState::Occupied : v == 254 ? CellState::Free : CellState::Unknown;
		}
	}
	return t;
}

TriStateGrid resampleTriState(
	const TriStateGrid& src, const mrpt::poses::CPose3D& T_B_A, const GridLattice& lattice, double scaleA)
{
	if (!(scaleA > 0)) throw std::invalid_argument("resampleTriState: scaleA must be > 0");
	TriStateGrid out;
	static_cast<GridLattice&>(out) = lattice;
	out.cells.assign(out.numCells(), CellState::Unknown);
	const mrpt::poses::CPose3D T_A_B = -T_B_A;
	for (int cy = 0; cy < out.sizeY; cy++)
		for (int cx = 0; cx < out.sizeX; cx++)
		{
			double ax, ay, az;
			T_A_B.composePoint(out.xMin + (cx + 0.5) * out.resolution, out.yMin + (cy + 0.5) * out.resolution, 0.0, ax, ay, az);
			out.cells[out.cellIndex(cx, cy)] = src.at(ax / scaleA, ay / scaleA);
		}
	return out;
}

}  // namespace keygrid::maps
