#pragma once
/** \file OccupancyGridMetrics.h
 * Accuracy of an estimated 2D occupancy grid against a ground-truth floor plan (e.g. the one
 * keygrid-sim writes): occupied-cell precision / recall / F1 with a distance tolerance,
 * free-space accuracy, and the navigation-safety metrics (hazard cells = obstacles called free,
 * obstacle recall over the boundary the cameras saw, free-space F1); the per-cell classes behind
 * them, an overlay image of the map on the plan (OccupancyGridMetrics_overlay.cpp) and the
 * visibility mask of the plan from rendered views (OccupancyGridMetrics_visibility.cpp).
 *
 * It lives in libs/maps, not libs/eval, because it reads CISMOccupancyGrid2D and libs/eval must
 * not depend on maps; the ground truth is a plain struct so a simulator can fill it without
 * linking maps.
 */
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <opencv2/core/mat.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace keygrid::maps
{
/** A lattice of square cells in a floor frame: cell (cx, cy) covers [xMin + cx res,
 * xMin + (cx+1) res) x [yMin + cy res, yMin + (cy+1) res); a grid on it stores its cells
 * row-major, index cx + cy * sizeX. */
struct GridLattice
{
	double resolution{0.05};
	double xMin{0}, yMin{0};
	int sizeX{0}, sizeY{0};

	bool contains(int cx, int cy) const { return cx >= 0 && cy >= 0 && cx < sizeX && cy < sizeY; }
	size_t cellIndex(int cx, int cy) const { return static_cast<size_t>(cx) + static_cast<size_t>(cy) * sizeX; }
	size_t numCells() const { return static_cast<size_t>(sizeX) * static_cast<size_t>(sizeY); }
};

/** A ground-truth floor plan on its own lattice, in the grid's floor frame. */
struct FloorPlanGrid : GridLattice
{
	enum Cell : uint8_t
	{
		Free = 0,
		Occupied = 1,
		Ignore = 2  ///< outside the mapped area: not scored
	};
	/** Bits of `seen`. */
	enum SeenBits : uint8_t
	{
		SeenSurface = 1,    ///< a surface point inside the height band was seen in the cell
		SeenFreeSpace = 2,  ///< a ray crossed the cell's column inside the band, or ended on its floor
		/** A ray crossed the cell's column below the band (zMin), or ended on its floor: the base
		 * of anything standing there was in view, the condition for calling a cell free without
		 * ever missing a low obstacle */
		SeenFloor = 4
	};
	std::vector<uint8_t> cells;  ///< row-major, index cx + cy * sizeX
	/** Optional visibility mask on the same lattice (SeenBits; markSeenCells() fills it). Empty =
	 * no mask: every cell counts as in view. An Occupied cell is in view with SeenSurface, a
	 * Free cell with SeenFreeSpace. Only the "seen" metrics use it. */
	std::vector<uint8_t> seen;

	/** A ground truth where every cell is scored: `occupied` (row-major, row 0 = lowest y,
	 * non-zero = Occupied, else Free) on a sizeX x sizeY lattice whose cell (0, 0) has its corner
	 * at (xMin, yMin), e.g. keygrid-sim's floor plan. Throws std::invalid_argument when the
	 * sizes disagree. */
	static FloorPlanGrid fromOccupancy(
		double resolution, double xMin, double yMin, int sizeX, int sizeY, const std::vector<uint8_t>& occupied);
	/** Ground truth at a floor-frame position; Ignore outside the lattice. */
	Cell at(double x, double y) const;
	Cell cell(int cx, int cy) const
	{
		if (!contains(cx, cy)) return Ignore;
		return static_cast<Cell>(cells[cellIndex(cx, cy)]);
	}
	/** Whether the cameras saw cell (cx, cy) in the sense of its class (true without a mask). */
	bool inView(int cx, int cy) const;
	/** Whether the cameras saw the floor-level space of cell (cx, cy) (SeenFloor; true without
	 * a mask). */
	bool floorInView(int cx, int cy) const;
};

struct OccupancyMetricsOptions
{
	/** An occupied cell matches an occupied cell of the other grid within this distance [m]
	 * (Default: 0.05 m = one 5 cm cell) */
	double matchTolerance{0.05};
	/** A ground-truth obstacle cell with no ground-truth free cell within this many cells
	 * (Chebyshev distance, so diagonal neighbours count as 1) is "interior": the map calling it
	 * free is a hazard that no registration or discretisation error of one cell explains
	 * (Default: 1 cell) */
	int hazardMarginCells{1};

	bool isValid(std::string* error = nullptr) const;
};

struct OccupancyMetrics
{
	/** Estimated occupied cells (in scored area) and those with GT occupied within tolerance. */
	size_t estOccupied{0}, estOccupiedMatched{0};
	/** GT occupied cells and those with an estimated occupied cell within tolerance. */
	size_t gtOccupied{0}, gtOccupiedMatched{0};
	double precision{0}, recall{0}, f1{0};
	/** GT free cells the estimate observed (free or occupied), and those it calls free. */
	size_t gtFreeObserved{0}, gtFreeCorrect{0};
	/** gtFreeCorrect / gtFreeObserved */
	double freeAccuracy{0};
	/** Diagnostic: the part of gtFreeObserved / gtFreeCorrect lying within matchTolerance of a
	 * GT-occupied cell (the one-cell band around walls, where a surface on a cell boundary makes
	 * the true cell ambiguous), and the free accuracy of the cells away from that band. */
	size_t gtFreeObservedNearOccupied{0}, gtFreeCorrectNearOccupied{0};
	double freeAccuracyAwayFromOccupied{0};
	/** Estimated free cells in scored area, and those GT free. */
	size_t estFree{0}, estFreeCorrect{0};
	/** estFreeCorrect / estFree */
	double freePrecision{0};

	// Navigation safety.
	/** GT-occupied cells farther than hazardMarginCells from every GT-free cell, and those the
	 * map calls FREE: hazardCells must be 0 for a navigation-safe map. */
	size_t gtOccupiedInterior{0}, hazardCells{0};
	/** All GT-occupied cells the map calls FREE (hazards plus obstacle edges within the margin). */
	size_t gtOccupiedCalledFree{0};
	/** Obstacle boundary: GT-occupied cells with a GT-free cell among their 8 neighbours, in
	 * view (FloorPlanGrid::seen, SeenSurface), and those with an estimated occupied cell within
	 * matchTolerance (the rule of `recall`). boundaryRecall = matched / seen. */
	size_t gtBoundarySeen{0}, gtBoundarySeenMatched{0};
	double boundaryRecall{0};
	/** GT-free cells in view (SeenFreeSpace; all GT-free cells without a mask) and those the map
	 * calls free. freeRecall = called free / in view. */
	size_t gtFreeSeen{0}, gtFreeSeenCalledFree{0};
	double freeRecall{0};
	/** Harmonic mean of freePrecision and freeRecall. */
	double freeF1{0};
	/** The same recall and F1 over the GT-free cells whose floor-level space was in view
	 * (SeenFloor): the free space a map can certify without risking a low obstacle. */
	size_t gtFreeFloorSeen{0}, gtFreeFloorSeenCalledFree{0};
	double freeRecallFloorSeen{0}, freeF1FloorSeen{0};
};

/** What a floor-plan cell is, comparing the estimate with the ground truth (the overlay's
 * colours; doc/maps-ism2d.md has the legend). */
enum class CellVerdict : uint8_t
{
	Unknown = 0,     ///< GT free, map unknown; or not scored (GT Ignore)
	Free,            ///< GT free, map free
	Occupied,        ///< map occupied, GT occupied within matchTolerance
	Missed,          ///< GT obstacle in view, map neither occupied (within tolerance) nor free
	MissedUnseen,    ///< same, but the cameras never saw the cell (only with a visibility mask)
	EdgeCalledFree,  ///< GT obstacle within hazardMarginCells of GT free, map free
	Hazard,          ///< interior GT obstacle, map free
	FalseObstacle    ///< GT free, map occupied, no GT obstacle within matchTolerance
};
constexpr int kCellVerdictCount = 8;
/** Short English name of a verdict (legend text). */
const char* cellVerdictName(CellVerdict v);

/** A tri-state grid on its own lattice (e.g. a map_2d.pgm re-read, or a grid resampled into
 * the ground truth's frame). */
struct TriStateGrid : GridLattice
{
	std::vector<CellState> cells;  ///< row-major, index cx + cy * sizeX
	/** Pose of the grid's floor frame in the world, when the file says so (keygrid's
	 * saveAsRosMapServer writes it as a comment line). */
	std::optional<mrpt::poses::CPose3D> T_world_floor;

	/** Unknown outside the lattice. */
	CellState cell(int cx, int cy) const
	{
		if (!contains(cx, cy)) return CellState::Unknown;
		return cells[cellIndex(cx, cy)];
	}
	CellState at(double x, double y) const
	{
		return cell(
			static_cast<int>(std::floor((x - xMin) / resolution)),
			static_cast<int>(std::floor((y - yMin) / resolution)));
	}
	/** The tri-states of a CISMOccupancyGrid2D (same lattice). */
	static TriStateGrid fromGrid(const CISMOccupancyGrid2D& g);
	/** Reads a ROS map_server pair as written by CISMOccupancyGrid2D::saveAsRosMapServer (P5
	 * pgm: 0 occupied, 254 free, other unknown). Throws std::runtime_error naming the file. */
	static TriStateGrid loadRosMapServer(const std::string& yamlPath);
};

/** Scores `est` against `gt` (cells compared at cell centres). Throws std::invalid_argument
 * naming the field for invalid options or a `gt.seen` of the wrong size. */
OccupancyMetrics evaluateOccupancy(
	const TriStateGrid& est, const FloorPlanGrid& gt, const OccupancyMetricsOptions& opts = {});
/** Same, on the grid's own lattice. */
OccupancyMetrics evaluateOccupancy(
	const CISMOccupancyGrid2D& est, const FloorPlanGrid& gt, const OccupancyMetricsOptions& opts = {});

/** The verdict of every cell of `gt` (row-major, gt's lattice; the estimate is read at the
 * cell centres). Counting them gives the metrics: #Hazard = hazardCells, #Free =
 * gtFreeCorrect, and so on. */
std::vector<CellVerdict> classifyCells(
	const TriStateGrid& est, const FloorPlanGrid& gt, const OccupancyMetricsOptions& opts = {});

struct OverlayImageOptions
{
	/** Image pixels per floor-plan cell, each direction (Default: 4) */
	int pixelsPerCell{4};
	/** Draw a legend (colour, meaning, cell count) under the map (Default: true) */
	bool legend{true};

	bool isValid(std::string* error = nullptr) const;
};

/** RGB colour of a verdict in the overlay image. */
std::array<uint8_t, 3> cellVerdictColour(CellVerdict v);

/** Writes the estimate laid over the floor plan as a colour image (PNG, or any format MRPT's
 * CImage writes by extension): one square of pixelsPerCell per plan cell coloured by its
 * verdict, +y up, with an optional legend. Throws std::runtime_error naming the file when it
 * cannot be written. Returns the verdict counts (index = CellVerdict). */
std::array<size_t, kCellVerdictCount> saveOverlayImage(
	const std::string& path, const TriStateGrid& est, const FloorPlanGrid& gt,
	const OccupancyMetricsOptions& metricOpts = {}, const OverlayImageOptions& imageOpts = {});

struct FloorPlanVisibilityOptions
{
	/** Height band of the plan [m, floor frame] (Default: 0.10 .. 1.80, keygrid-sim's plan) */
	double zMin{0.10}, zMax{1.80};
	/** Largest horizontal distance from the camera that counts as seen [m] (Default: 4.5, the
	 * 2D grid's maxRange) */
	double maxRange{4.5};
	/** A point with |z| below this is floor [m] (Default: 0.04, the grid's floorTolerance) */
	double floorTolerance{0.04};
	/** Free space: every n-th pixel in u and v is traced (Default: 4); surfaces use every pixel */
	int freeRayStride{4};

	bool isValid(std::string* error = nullptr) const;
};

/** Adds to `gt.seen` (sized on first use) what one noise-free depth image (CV_32FC1, metres
 * along the optical axis, 0 = no return; pinhole `cam`, distortion ignored) taken at
 * T_floor_cam (optical frame) shows of the plan: SeenSurface in the cell of every point inside
 * [zMin, zMax] within maxRange (a point within 1 mm of a cell boundary marks both cells: plan
 * surfaces lie on boundaries); SeenFreeSpace in every cell the ray's part inside the band
 * crosses before the point's own cell (clipped at maxRange), and in the cell of a floor point;
 * SeenFloor likewise for the ray's part below zMin.
 * Throws std::invalid_argument on a depth image of the wrong type or size. */
void markSeenCells(
	FloorPlanGrid& gt, const cv::Mat& depth, const core::RgbdCamera& cam,
	const mrpt::poses::CPose3D& T_floor_cam, const FloorPlanVisibilityOptions& opts = {});

/** Resamples `src` (a grid in floor frame A) onto `lattice` in floor frame B (e.g. a ground
 * truth's): each output cell takes the state of the source cell under its centre (nearest
 * neighbour), the centre (x, y, 0)_B mapped into A by inv(T_B_A) and its A-height dropped (a
 * small tilt between the two floors is ignored; the caller should report it). `scaleA` is the
 * length in B of one unit of A (a map in another unit, e.g. a monocular map aligned by a
 * similarity: a point p_A lies at T_B_A (scaleA p_A)); it must be > 0. The result has no
 * T_world_floor. */
TriStateGrid resampleTriState(
	const TriStateGrid& src, const mrpt::poses::CPose3D& T_B_A, const GridLattice& lattice, double scaleA = 1.0);

}  // namespace keygrid::maps
