#pragma once
/** \file OctomapBinaryReader.h
 * Reads OctoMap's binary tree format (.bt, an OcTree written with writeBinary(), e.g. keygrid's
 * map_3d.bt) into lists of full-depth voxels, without liboctomap. The format is the one
 * OctomapBinaryWriter.h describes; a pruned leaf above full depth stands for every voxel under
 * it. The header's comment lines are kept: keygrid-slam writes the map's floor frame in one
 * (ExportFrame.h, floorFrameComment()).
 */
#include <mrpt/poses/CPose3D.h>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace keygrid::maps
{
struct OctomapBinaryVoxels
{
	/** Voxel (x, y, z) covers [x res, (x+1) res) per axis of the map's frame (OctoMap key minus
	 * 32768). */
	using Index = std::array<int32_t, 3>;

	/** Voxel size [m] (the header's `res`) */
	double resolution{0};
	/** The header's comment lines, without their leading "# " */
	std::vector<std::string> comments;
	/** The frame the map was written in, from a "keygrid T_world_floor" comment; nullopt when the
	 * file has none (keygrid-slam: no floor known, the map is in the SLAM world). */
	std::optional<mrpt::poses::CPose3D> T_world_floor;
	/** Occupied and free voxels in depth-first (Morton) order; unknown space is in neither. */
	std::vector<Index> occupied, free;
};

/** Reads a .bt file. Throws std::runtime_error naming the file on a missing file, a header that
 * is not OctoMap's OcTree binary header, or a truncated tree. */
OctomapBinaryVoxels readOctomapBinary(const std::string& path);

}  // namespace keygrid::maps
