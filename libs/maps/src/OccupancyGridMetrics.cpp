#include <keygrid/maps/OccupancyGridMetrics.h>
#include <mrpt/math/CQuaternion.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>

namespace keygrid::maps
{
FloorPlanGrid::Cell FloorPlanGrid::at(double x, double y) const
{
	return cell(
		static_cast<int>(std::floor((x - xMin) / resolution)),
		static_cast<int>(std::floor((y - yMin) / resolution)));
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

OccupancyMetrics evaluate(const EstView& est, const FloorPlanGrid& gt, const OccupancyMetricsOptions& opts)
{
	const int sizeXEst = est.sizeX, sizeYEst = est.sizeY;
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
	for (int cy = 0; cy < sizeYEst; cy++)
		for (int cx = 0; cx < sizeXEst; cx++)
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
				if (gtHasOccupiedNear(x, y))
				{
					m.gtFreeObservedNearOccupied++;
					if (s == CellState::Free) m.gtFreeCorrectNearOccupied++;
				}
			}
		}
	auto ratio = [](size_t a, size_t b) { return b ? static_cast<double>(a) / static_cast<double>(b) : 0.0; };
	m.precision = ratio(m.estOccupiedMatched, m.estOccupied);
	m.recall = ratio(m.gtOccupiedMatched, m.gtOccupied);
	m.f1 = (m.precision + m.recall) > 0 ? 2 * m.precision * m.recall / (m.precision + m.recall) : 0.0;
	m.freeAccuracy = ratio(m.gtFreeCorrect, m.gtFreeObserved);
	m.freeAccuracyAwayFromOccupied = ratio(
		m.gtFreeCorrect - m.gtFreeCorrectNearOccupied, m.gtFreeObserved - m.gtFreeObservedNearOccupied);
	m.freePrecision = ratio(m.estFreeCorrect, m.estFree);
	return m;
}
}  // namespace

OccupancyMetrics evaluateOccupancy(
	const TriStateGrid& est, const FloorPlanGrid& gt, const OccupancyMetricsOptions& opts)
{
	return evaluate(
		EstView{est.resolution, est.xMin, est.yMin, est.sizeX, est.sizeY,
			[&](int cx, int cy) { return est.cell(cx, cy); }},
		gt, opts);
}

OccupancyMetrics evaluateOccupancy(
	const CISMOccupancyGrid2D& est, const FloorPlanGrid& gt, const OccupancyMetricsOptions& opts)
{
	return evaluate(
		EstView{est.resolution(), est.xMin(), est.yMin(), est.sizeX(), est.sizeY(),
			[&](int cx, int cy) { return est.cellState(cx, cy); }},
		gt, opts);
}

TriStateGrid TriStateGrid::fromGrid(const CISMOccupancyGrid2D& g)
{
	TriStateGrid t;
	t.resolution = g.resolution();
	t.xMin = g.xMin();
	t.yMin = g.yMin();
	t.sizeX = g.sizeX();
	t.sizeY = g.sizeY();
	t.cells.resize(static_cast<size_t>(t.sizeX) * static_cast<size_t>(t.sizeY));
	for (int cy = 0; cy < t.sizeY; cy++)
		for (int cx = 0; cx < t.sizeX; cx++)
			t.cells[static_cast<size_t>(cx) + static_cast<size_t>(cy) * t.sizeX] = g.cellState(cx, cy);
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
		else if (line.rfind("# keygrid T_world_floor", 0) == 0 && line.find(':') != std::string::npos)
		{
			double v[7];
			std::istringstream is(line.substr(line.find(':') + 1));
			if (is >> v[0] >> v[1] >> v[2] >> v[3] >> v[4] >> v[5] >> v[6])
				t.T_world_floor = mrpt::poses::CPose3D(
					mrpt::math::CQuaternionDouble(v[6], v[3], v[4], v[5]), v[0], v[1], v[2]);
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
	std::vector<unsigned char> img(static_cast<size_t>(t.sizeX) * static_cast<size_t>(t.sizeY));
	pgm.read(reinterpret_cast<char*>(img.data()), static_cast<std::streamsize>(img.size()));
	if (!pgm) throw std::runtime_error("'" + pgmPath + "': truncated pixel data");
	t.cells.resize(img.size());
	for (int r = 0; r < t.sizeY; r++)
	{
		const int cy = t.sizeY - 1 - r;  // image row 0 = largest y
		for (int cx = 0; cx < t.sizeX; cx++)
		{
			const unsigned char v = img[static_cast<size_t>(r) * t.sizeX + cx];
			t.cells[static_cast<size_t>(cx) + static_cast<size_t>(cy) * t.sizeX] =
				v == 0 ? CellState::Occupied : v == 254 ? CellState::Free : CellState::Unknown;
		}
	}
	return t;
}

TriStateGrid resampleTriState(
	const TriStateGrid& src, const mrpt::poses::CPose3D& T_B_A, const TriStateGrid& like)
{
	TriStateGrid out;
	out.resolution = like.resolution;
	out.xMin = like.xMin;
	out.yMin = like.yMin;
	out.sizeX = like.sizeX;
	out.sizeY = like.sizeY;
	out.T_world_floor = like.T_world_floor;
	out.cells.assign(static_cast<size_t>(out.sizeX) * static_cast<size_t>(out.sizeY), CellState::Unknown);
	const mrpt::poses::CPose3D T_A_B = -T_B_A;
	for (int cy = 0; cy < out.sizeY; cy++)
		for (int cx = 0; cx < out.sizeX; cx++)
		{
			double ax, ay, az;
			T_A_B.composePoint(out.xMin + (cx + 0.5) * out.resolution, out.yMin + (cy + 0.5) * out.resolution, 0.0, ax, ay, az);
			out.cells[static_cast<size_t>(cx) + static_cast<size_t>(cy) * out.sizeX] = src.at(ax, ay);
		}
	return out;
}

}  // namespace keygrid::maps
