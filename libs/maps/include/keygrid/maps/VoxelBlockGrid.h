#pragma once
/** \file VoxelBlockGrid.h
 * Sparse voxel storage: dense 8x8x8 blocks of voxels in a hash map keyed by block index, so the
 * extent is unbounded and memory follows the observed volume (the voxblox layout). This is a
 * container only: ray casting, integration, conflict detection and morphing live elsewhere.
 *
 * Voxel (i,j,k) covers [i*res, (i+1)*res) x [j*res, ...) x [k*res, ...) in the grid's frame
 * (the world frame of the map); its centre is ((i+0.5)*res, ...). This is the same cell
 * convention as OctoMap (key = floor(x/res) + 32768), so voxels map 1:1 onto OcTree leaves.
 */
#include <keygrid/maps/FloorToInt.h>
#include <mrpt/math/TPoint3D.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <unordered_map>

namespace keygrid
{
/** Integer index of a voxel (or of a block, depending on context). */
struct VoxelIndex
{
	int32_t x{0}, y{0}, z{0};

	bool operator==(const VoxelIndex& o) const { return x == o.x && y == o.y && z == o.z; }
	bool operator!=(const VoxelIndex& o) const { return !(*this == o); }
	bool operator<(const VoxelIndex& o) const
	{
		if (x != o.x) return x < o.x;
		if (y != o.y) return y < o.y;
		return z < o.z;
	}
};

struct VoxelIndexHash
{
	std::size_t operator()(const VoxelIndex& v) const
	{
		// Large primes (Teschner et al. 2003 spatial hashing).
		return static_cast<std::size_t>(
			(static_cast<uint64_t>(static_cast<uint32_t>(v.x)) * 73856093u) ^
			(static_cast<uint64_t>(static_cast<uint32_t>(v.y)) * 19349669u) ^
			(static_cast<uint64_t>(static_cast<uint32_t>(v.z)) * 83492791u));
	}
};

/** Contents of one voxel: 8 bytes. */
struct Voxel
{
	/** Occupancy log-odds log(p/(1-p)); 0 = unknown prior (p = 0.5). */
	float logOdds{0.0f};
	/** Travelled distance [m] of the camera that last updated this voxel; negative = never
	 * updated (the voxel is unknown). */
	float travelled{-1.0f};

	bool isKnown() const { return travelled >= 0.0f; }
};

/** A dense cube of kBlockSide^3 voxels, x fastest. */
struct VoxelBlock
{
	static constexpr int kSideLog2 = 3;
	static constexpr int kSide = 1 << kSideLog2;  //!< 8 voxels per side
	static constexpr int kVoxels = kSide * kSide * kSide;  //!< 512 voxels per block

	std::array<Voxel, kVoxels> voxels{};

	static int linear(int lx, int ly, int lz) { return lx + kSide * (ly + kSide * lz); }
	Voxel& at(int lx, int ly, int lz) { return voxels[linear(lx, ly, lz)]; }
	const Voxel& at(int lx, int ly, int lz) const { return voxels[linear(lx, ly, lz)]; }
};

/** Sparse grid of VoxelBlock. Not thread-safe for allocation; concurrent writes to voxels of
 * already-allocated, distinct blocks are safe (the integrator relies on it). */
class VoxelBlockGrid
{
   public:
	using BlockMap = std::unordered_map<VoxelIndex, std::unique_ptr<VoxelBlock>, VoxelIndexHash>;

	/** \param resolution Voxel edge length [m], > 0. Throws std::invalid_argument otherwise. */
	explicit VoxelBlockGrid(double resolution = 0.05);

	VoxelBlockGrid(const VoxelBlockGrid& o);
	VoxelBlockGrid& operator=(const VoxelBlockGrid& o);
	VoxelBlockGrid(VoxelBlockGrid&&) = default;
	VoxelBlockGrid& operator=(VoxelBlockGrid&&) = default;

	double resolution() const { return m_res; }
	/** Removes all blocks (keeps the resolution). */
	void clear() { m_blocks.clear(); }
	/** Removes all blocks and changes the resolution. */
	void reset(double resolution);

	/** Voxel containing the point p [m] (floor(p / res)). */
	VoxelIndex voxelOf(const mrpt::math::TPoint3D& p) const
	{
		return {floorToInt(p.x * m_invRes), floorToInt(p.y * m_invRes), floorToInt(p.z * m_invRes)};
	}
	/** Centre [m] of voxel v. */
	mrpt::math::TPoint3D centreOf(const VoxelIndex& v) const
	{
		return {(v.x + 0.5) * m_res, (v.y + 0.5) * m_res, (v.z + 0.5) * m_res};
	}

	/** Block holding voxel v (arithmetic shift = floor division by 8, also for negatives). */
	static VoxelIndex blockOf(const VoxelIndex& v)
	{
		return {
			v.x >> VoxelBlock::kSideLog2, v.y >> VoxelBlock::kSideLog2,
			v.z >> VoxelBlock::kSideLog2};
	}
	/** Index of the first voxel of block b. */
	static VoxelIndex firstVoxelOf(const VoxelIndex& b)
	{
		return {b.x * VoxelBlock::kSide, b.y * VoxelBlock::kSide, b.z * VoxelBlock::kSide};
	}
	/** Position of voxel v inside its block, each in [0, 8). */
	static int localLinear(const VoxelIndex& v)
	{
		constexpr int m = VoxelBlock::kSide - 1;
		return VoxelBlock::linear(v.x & m, v.y & m, v.z & m);
	}

	/** The voxel, or nullptr when its block is not allocated. */
	const Voxel* find(const VoxelIndex& v) const;
	Voxel* find(const VoxelIndex& v);
	/** The voxel, allocating its block (all voxels unknown) when needed. */
	Voxel& at(const VoxelIndex& v);

	/** Block b, or nullptr. */
	const VoxelBlock* findBlock(const VoxelIndex& b) const;
	/** Block b, allocated when needed. */
	VoxelBlock& blockAt(const VoxelIndex& b);

	const BlockMap& blocks() const { return m_blocks; }
	std::size_t numBlocks() const { return m_blocks.size(); }
	std::size_t numAllocatedVoxels() const { return m_blocks.size() * VoxelBlock::kVoxels; }
	/** Voxels that were updated at least once. */
	std::size_t numKnownVoxels() const;
	/** Known voxels with logOdds > threshold. */
	std::size_t numOccupiedVoxels(float logOddsThreshold = 0.0f) const;

	/** Heap bytes used by blocks plus the hash table's buckets and nodes (an estimate of the
	 * std::unordered_map overhead: one node with key, pointer and next pointer per block). */
	std::size_t memoryBytes() const;
	/** Bytes per allocated voxel (memoryBytes / numAllocatedVoxels), 0 when empty. */
	double bytesPerAllocatedVoxel() const;

	/** Calls f(voxelIndex, voxel) for every known voxel. Iteration order is the hash map's. */
	void forEachKnown(const std::function<void(const VoxelIndex&, const Voxel&)>& f) const;

	/** Same blocks, same voxels (exact float comparison). */
	bool operator==(const VoxelBlockGrid& o) const;

   private:
	double m_res{0.05};
	double m_invRes{20.0};
	BlockMap m_blocks;
};

}  // namespace keygrid
