#pragma once
/** \file OccupancyGridMetrics.h
 * Accuracy of an estimated 2D occupancy grid against a ground-truth floor plan (e.g. the one
 * keygrid-sim writes): occupied-cell precision / recall / F1 with a distance tolerance, and
 * free-space accuracy.
 *
 * It lives in libs/maps, not libs/eval, because it reads CISMOccupancyGrid2D and libs/eval must
 * not depend on maps; the ground truth is a plain struct so a simulator can fill it without
 * linking maps.
 */
#include <keygrid/maps/CISMOccupancyGrid2D.h>

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace keygrid::maps
{
/** A ground-truth floor plan on its own lattice, in the grid's floor frame. */
struct FloorPlanGrid
{
	enum Cell : uint8_t
	{
		Free = 0,
		Occupied = 1,
		Ignore = 2  ///< outside the mapped area: not scored
	};
	double resolution{0.05};
	double xMin{0}, yMin{0};
	int sizeX{0}, sizeY{0};
	std::vector<uint8_t> cells;  ///< row-major, index cx + cy * sizeX

	/** Ground truth at a floor-frame position; Ignore outside the lattice. */
	Cell at(double x, double y) const;
	Cell cell(int cx, int cy) const
	{
		if (cx < 0 || cy < 0 || cx >= sizeX || cy >= sizeY) return Ignore;
		return static_cast<Cell>(cells[static_cast<size_t>(cx) + static_cast<size_t>(cy) * sizeX]);
	}
};

struct OccupancyMetricsOptions
{
	/** An occupied cell matches an occupied cell of the other grid within this distance [m]
	 * (Default: 0.05 m = one 5 cm cell) */
	double matchTolerance{0.05};
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
};

/** A tri-state grid on its own lattice (e.g. a map_2d.pgm re-read, or a grid resampled into
 * the ground truth's frame). Cell (cx, cy) covers [xMin + cx res, xMin + (cx+1) res) x ... */
struct TriStateGrid
{
	double resolution{0.05};
	double xMin{0}, yMin{0};
	int sizeX{0}, sizeY{0};
	std::vector<CellState> cells;  ///< row-major, index cx + cy * sizeX
	/** Pose of the grid's floor frame in the world, when the file says so (keygrid's
	 * saveAsRosMapServer writes it as a comment line). */
	std::optional<mrpt::poses::CPose3D> T_world_floor;

	/** Unknown outside the lattice. */
	CellState cell(int cx, int cy) const
	{
		if (cx < 0 || cy < 0 || cx >= sizeX || cy >= sizeY) return CellState::Unknown;
		return cells[static_cast<size_t>(cx) + static_cast<size_t>(cy) * sizeX];
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

/** Scores `est` against `gt` (cells compared at cell centres). */
OccupancyMetrics evaluateOccupancy(
	const TriStateGrid& est, const FloorPlanGrid& gt, const OccupancyMetricsOptions& opts = {});
/** Same, on the grid's own lattice. */
OccupancyMetrics evaluateOccupancy(
	const CISMOccupancyGrid2D& est, const FloorPlanGrid& gt, const OccupancyMetricsOptions& opts = {});

/** Resamples `src` (a grid in floor frame A) onto the lattice of `like` in floor frame B:
 * each output cell takes the state of the source cell under its centre (nearest neighbour),
 * the centre (x, y, 0)_B mapped into A by inv(T_B_A) and its A-height dropped (a small tilt
 * between the two floors is ignored; the caller should report it). */
TriStateGrid resampleTriState(
	const TriStateGrid& src, const mrpt::poses::CPose3D& T_B_A, const TriStateGrid& like);

}  // namespace keygrid::maps
