#pragma once
/** \file GroundTruthOccupancy.h
 * Ground-truth occupancy of the STATIC part of a scene (objects with dynamic = false), in the
 * world frame (metres, z up), for scoring maps:
 * - VoxelSet: the voxels the object SURFACES pass through (what a depth sensor can observe;
 *   the inside of a solid box is not marked). Voxel (i, j, k) is the half-open cube
 *   [origin + (i, j, k) * res, origin + (i+1, j+1, k+1) * res).
 * - FloorPlan: 2D cells the surfaces pass through within a height band [zMin, zMax], saved as
 *   a ROS map_server pair (PGM + YAML).
 * File formats: doc/simulator.md.
 */
#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace keygrid::sim
{
class Scene;

class VoxelSet
{
   public:
	using Index = std::array<int, 3>;

	VoxelSet() = default;
	/** resolution > 0 [m]; origin [m] is the corner of voxel (0, 0, 0). */
	VoxelSet(double resolution, const Eigen::Vector3d& origin);

	double resolution() const { return m_res; }
	const Eigen::Vector3d& origin() const { return m_origin; }
	/** Sorted, unique. */
	const std::vector<Index>& voxels() const { return m_voxels; }
	std::size_t size() const { return m_voxels.size(); }

	Index indexOf(const Eigen::Vector3d& p) const;
	Eigen::Vector3d centre(const Index& v) const;
	bool contains(const Index& v) const;
	bool containsPoint(const Eigen::Vector3d& p) const { return contains(indexOf(p)); }

	/** Adds voxels (call finalize() before queries). */
	void insert(const Index& v) { m_voxels.push_back(v); }
	void insertPoint(const Eigen::Vector3d& p) { insert(indexOf(p)); }
	/** Sorts and removes duplicates. */
	void finalize();

	/** Text format "KEYGRID_VOXELS 1" (see doc/simulator.md). Throws on I/O failure. */
	void save(const std::string& path) const;
	/** Throws std::runtime_error naming file:line on a malformed file or unknown version. */
	static VoxelSet load(const std::string& path);

   private:
	double m_res{0.05};
	Eigen::Vector3d m_origin{0, 0, 0};
	std::vector<Index> m_voxels;
};

/** 2D occupancy grid. Cell (cx, cy) is [origin + (cx, cy) * res, origin + (cx+1, cy+1) * res). */
struct FloorPlan
{
	double resolution{0.05};             //!< [m]
	Eigen::Vector2d origin{0, 0};        //!< world x, y of the corner of cell (0, 0) [m]
	int width{0}, height{0};             //!< cells along x, y
	std::vector<std::uint8_t> occupied;  //!< row-major, row 0 = lowest y; 1 = occupied

	bool inside(int cx, int cy) const { return cx >= 0 && cy >= 0 && cx < width && cy < height; }
	bool occupiedAt(int cx, int cy) const { return inside(cx, cy) && occupied[cy * width + cx]; }
	/** Cell of world point (x, y) (may be outside the grid). */
	std::array<int, 2> cellOf(double x, double y) const;
	std::size_t occupiedCount() const;

	/** Writes `<stem>.pgm` (occupied 0, free 254, top row = highest y) and `<stem>.yaml`
	 * (ROS map_server keys: image, resolution, origin, negate, occupied_thresh, free_thresh). */
	void save(const std::string& stem) const;
	/** Reads a map_server YAML + its image (occupied where (255 - v) / 255 > occupied_thresh). */
	static FloorPlan load(const std::string& yamlPath);
};

/** Surface voxels of the static objects. Surfaces are sampled at spacing resolution / 2
 * including their edges, which is exact for faces aligned with the grid axes. */
VoxelSet voxeliseStaticScene(
	const Scene& scene, double resolution, const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

/** Cells crossed by static surfaces with zMin <= z <= zMax; the grid covers the static
 * objects' bounds plus one cell, its origin on a multiple of the resolution.
 * A surface counts for every *closed* cell it touches: a wall lying exactly on the line between
 * two cells (the usual case for walls at whole-metre coordinates and 5 cm cells) marks both,
 * since either cell holds a point of it and a sensor's points scatter into both. With half-open
 * cells the choice would depend on the side the room is on (x = 0 inside, x = 6 outside).
 * "Exactly" means within kFloorPlanBoundaryTolerance. */
FloorPlan floorPlanOfStaticScene(const Scene& scene, double resolution, double zMin, double zMax);

/** [m] distance to a cell boundary under which a surface point counts for both cells. */
constexpr double kFloorPlanBoundaryTolerance = 1e-7;
}  // namespace keygrid::sim
