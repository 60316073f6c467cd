#pragma once
/** \file GridMorphingDetail.h
 * Private to GridMorphing.cpp (setup, steps 1, 3, 4 of morphAndMerge) and GridMorphingBlocks.cpp
 * (step 2, the weighted averages per corrected block): the prepared keyframes and the per source
 * block summaries they share.
 */
#include <keygrid/maps/GridMorphing.h>
#include <keygrid/maps/VoxelBlockGrid.h>
#include <mrpt/poses/CPose3D.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace keygrid::detail::morphing
{
/** Rigid transform as a 3x4 matrix: p' = R p + t. */
struct Rigid
{
	double m[12];
	explicit Rigid(const mrpt::poses::CPose3D& T)
	{
		const auto R = T.getRotationMatrix();
		for (int r = 0; r < 3; ++r)
		{
			for (int c = 0; c < 3; ++c) m[4 * r + c] = R(r, c);
			m[4 * r + 3] = T.m_coords[r];
		}
	}
	mrpt::math::TPoint3D operator()(const mrpt::math::TPoint3D& p) const
	{
		return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3],
			m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
			m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
	}
};

/** Travelled distances of the known voxels of one source block: distinct values, ascending,
 * and the number of voxels with a value <= each. */
struct TravelHistogram
{
	std::vector<float> travel;
	std::vector<uint32_t> cumCount;
	/** Per distinct value: bounding box of its voxels, local indices in [0, kSide): lo x y z,
	 * hi x y z. */
	std::vector<std::array<uint8_t, 6>> box;
	/** Per distinct value: its voxels as a bit mask, word z, bit x + 8 y (local indices). */
	std::vector<std::array<uint64_t, VoxelBlock::kSide>> mask;

	/** Indices [i, j) of the distinct values in [lo, hi]. */
	std::pair<std::size_t, std::size_t> range(double lo, double hi) const
	{
		auto less = [](float a, double b) { return double(a) < b; };
		const std::size_t i = std::lower_bound(travel.begin(), travel.end(), lo, less) - travel.begin();
		const std::size_t j = std::upper_bound(travel.begin(), travel.end(), hi,
								  [](double b, float a) { return b < double(a); }) - travel.begin();
		return {i, std::max(i, j)};
	}

	/** Voxels with the distinct values [i, j). */
	std::size_t count(std::size_t i, std::size_t j) const
	{
		return j <= i ? 0 : cumCount[j - 1] - (i > 0 ? cumCount[i - 1] : 0);
	}
};

/** What step 2 needs of one source block. */
struct SourceBlockInfo
{
	const VoxelBlock* block;
	TravelHistogram travels;
};

/** Source block infos by block index: a dense array over the blocks' bounding box when that
 * holds at most 2^20 blocks (rooms to buildings at 5 cm), else the hash map. */
class SourceIndex
{
   public:
	explicit SourceIndex(std::unordered_map<VoxelIndex, SourceBlockInfo, VoxelIndexHash>&& m)
		: m_map(std::move(m))
	{
		if (m_map.empty()) return;
		m_lo = m_hi = m_map.begin()->first;
		for (const auto& kv : m_map)
		{
			const VoxelIndex& b = kv.first;
			m_lo = {std::min(m_lo.x, b.x), std::min(m_lo.y, b.y), std::min(m_lo.z, b.z)};
			m_hi = {std::max(m_hi.x, b.x), std::max(m_hi.y, b.y), std::max(m_hi.z, b.z)};
		}
		m_nx = int64_t(m_hi.x) - m_lo.x + 1, m_ny = int64_t(m_hi.y) - m_lo.y + 1;
		const int64_t cells = m_nx * m_ny * (int64_t(m_hi.z) - m_lo.z + 1);
		if (cells > (int64_t(1) << 20)) return;
		m_dense.assign(static_cast<std::size_t>(cells), nullptr);
		for (const auto& kv : m_map) m_dense[cell(kv.first)] = &kv.second;
	}
	const SourceBlockInfo* find(const VoxelIndex& b) const
	{
		if (m_dense.empty())
		{
			const auto it = m_map.find(b);
			return it == m_map.end() ? nullptr : &it->second;
		}
		if (b.x < m_lo.x || b.y < m_lo.y || b.z < m_lo.z || b.x > m_hi.x || b.y > m_hi.y || b.z > m_hi.z)
			return nullptr;
		return m_dense[cell(b)];
	}

   private:
	std::size_t cell(const VoxelIndex& b) const
	{
		return static_cast<std::size_t>(((int64_t(b.z) - m_lo.z) * m_ny + (int64_t(b.y) - m_lo.y)) * m_nx +
			(int64_t(b.x) - m_lo.x));
	}
	std::unordered_map<VoxelIndex, SourceBlockInfo, VoxelIndexHash> m_map;
	VoxelIndex m_lo, m_hi;
	int64_t m_nx{0}, m_ny{0};
	std::vector<const SourceBlockInfo*> m_dense;
};

/** A corrected keyframe prepared for the per-voxel loop. */
struct PreparedKeyframe
{
	const MorphKeyframe* kf;
	const VoxelBlockGrid* grid;
	Rigid worldToCamNew;  //!< inv(T_new)
	Rigid newToOld;  //!< T_old * inv(T_new): corrected world -> old world
	Rigid oldToNew;  //!< T_new * inv(T_old)
	mrpt::math::TPoint3D centreNew;
	mrpt::math::TPoint3D lo, hi;  //!< AABB of the corrected view cone
	/** Inward unit normals (camera frame) of the 4 side planes of the image pyramid. */
	double planes[4][3];
	/** The 5 faces through the camera centre in the world frame: the optical axis (z > 0) and
	 * the 4 side planes; a world point p is inside face f when face[f] . (p - centreNew) >= 0. */
	double face[5][3];
};

/** Step 2 of morphAndMerge: every voxel of the corrected blocks `outBlocks` (sorted by block
 * index) that a lookup in a view cone reaches gets the weighted average of the earlier log-odds;
 * voxels no lookup reaches stay as they are. `sources[s]` summarises source grid s. Adds its
 * counts to `st`. */
void averageOverCones(const std::vector<std::pair<VoxelIndex, VoxelBlock*>>& outBlocks,
	const std::vector<PreparedKeyframe>& kfs, const std::vector<SourceIndex>& sources,
	const MorphingOptions& opts, double res, MorphingStats& st);

}  // namespace keygrid::detail::morphing
