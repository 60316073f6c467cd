#include <keygrid/maps/VoxelBlockGrid.h>

#include <stdexcept>
#include <string>

namespace keygrid
{
VoxelBlockGrid::VoxelBlockGrid(double resolution) { reset(resolution); }

VoxelBlockGrid::VoxelBlockGrid(const VoxelBlockGrid& o) : m_res(o.m_res), m_invRes(o.m_invRes)
{
	m_blocks.reserve(o.m_blocks.size());
	for (const auto& [idx, blk] : o.m_blocks)
		m_blocks.emplace(idx, std::make_unique<VoxelBlock>(*blk));
}

VoxelBlockGrid& VoxelBlockGrid::operator=(const VoxelBlockGrid& o)
{
	if (this != &o)
	{
		VoxelBlockGrid tmp(o);
		*this = std::move(tmp);
	}
	return *this;
}

void VoxelBlockGrid::reset(double resolution)
{
	if (!(resolution > 0.0) || !std::isfinite(resolution))
		throw std::invalid_argument(
			"VoxelBlockGrid: resolution must be > 0 m, got " + std::to_string(resolution));
	m_res = resolution;
	m_invRes = 1.0 / resolution;
	m_blocks.clear();
}

const Voxel* VoxelBlockGrid::find(const VoxelIndex& v) const
{
	const auto it = m_blocks.find(blockOf(v));
	if (it == m_blocks.end()) return nullptr;
	return &it->second->voxels[localLinear(v)];
}

Voxel* VoxelBlockGrid::find(const VoxelIndex& v)
{
	const auto it = m_blocks.find(blockOf(v));
	if (it == m_blocks.end()) return nullptr;
	return &it->second->voxels[localLinear(v)];
}

Voxel& VoxelBlockGrid::at(const VoxelIndex& v) { return blockAt(blockOf(v)).voxels[localLinear(v)]; }

const VoxelBlock* VoxelBlockGrid::findBlock(const VoxelIndex& b) const
{
	const auto it = m_blocks.find(b);
	return it == m_blocks.end() ? nullptr : it->second.get();
}

VoxelBlock& VoxelBlockGrid::blockAt(const VoxelIndex& b)
{
	auto& slot = m_blocks[b];
	if (!slot) slot = std::make_unique<VoxelBlock>();
	return *slot;
}

std::size_t VoxelBlockGrid::numKnownVoxels() const
{
	std::size_t n = 0;
	for (const auto& kv : m_blocks)
		for (const Voxel& v : kv.second->voxels) n += v.isKnown() ? 1 : 0;
	return n;
}

std::size_t VoxelBlockGrid::numOccupiedVoxels(float thr) const
{
	std::size_t n = 0;
	for (const auto& kv : m_blocks)
		for (const Voxel& v : kv.second->voxels) n += (v.isKnown() && v.logOdds > thr) ? 1 : 0;
	return n;
}

std::size_t VoxelBlockGrid::memoryBytes() const
{
	// Node: key (12 B) + unique_ptr (8 B) + next pointer (8 B) + cached hash (8 B).
	constexpr std::size_t nodeBytes = sizeof(VoxelIndex) + sizeof(void*) * 3;
	return m_blocks.size() * (sizeof(VoxelBlock) + nodeBytes) +
		   m_blocks.bucket_count() * sizeof(void*) + sizeof(*this);
}

double VoxelBlockGrid::bytesPerAllocatedVoxel() const
{
	const std::size_t n = numAllocatedVoxels();
	return n == 0 ? 0.0 : static_cast<double>(memoryBytes()) / static_cast<double>(n);
}

void VoxelBlockGrid::forEachKnown(
	const std::function<void(const VoxelIndex&, const Voxel&)>& f) const
{
	for (const auto& [b, blk] : m_blocks)
	{
		const VoxelIndex o = firstVoxelOf(b);
		for (int lz = 0; lz < VoxelBlock::kSide; ++lz)
			for (int ly = 0; ly < VoxelBlock::kSide; ++ly)
				for (int lx = 0; lx < VoxelBlock::kSide; ++lx)
				{
					const Voxel& v = blk->at(lx, ly, lz);
					if (v.isKnown()) f(VoxelIndex{o.x + lx, o.y + ly, o.z + lz}, v);
				}
	}
}

bool VoxelBlockGrid::operator==(const VoxelBlockGrid& o) const
{
	if (m_res != o.m_res) return false;
	// Blocks that hold no known voxel are equivalent to absent blocks.
	auto sameAsUnknown = [](const VoxelBlock& b) {
		for (const Voxel& v : b.voxels)
			if (v.isKnown()) return false;
		return true;
	};
	for (const auto& [b, blk] : m_blocks)
	{
		const VoxelBlock* ob = o.findBlock(b);
		if (!ob)
		{
			if (!sameAsUnknown(*blk)) return false;
			continue;
		}
		for (int i = 0; i < VoxelBlock::kVoxels; ++i)
		{
			const Voxel& a = blk->voxels[i];
			const Voxel& c = ob->voxels[i];
			if (a.isKnown() != c.isKnown()) return false;
			if (a.isKnown() && (a.logOdds != c.logOdds || a.travelled != c.travelled)) return false;
		}
	}
	for (const auto& [b, blk] : o.m_blocks)
		if (!findBlock(b) && !sameAsUnknown(*blk)) return false;
	return true;
}

}  // namespace keygrid
