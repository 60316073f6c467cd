#pragma once
/** \file OctomapBinaryWriter.h
 * OctoMap's binary tree format (.bt) written straight from a list of voxels, without building
 * an octomap::OcTree (which holds ~30 bytes per voxel before pruning; this writer holds 8).
 *
 * The output is what OctoMap writes for an OcTree whose voxels were set at full depth, then
 * made maximum-likelihood and pruned (OcTree::toMaxLikelihood(), prune(), writeBinary()):
 * * the tree has 16 levels; a voxel's key per axis is floor(x / resolution) + 32768;
 * * the child index of a node below level L is bit L-1 of key x, plus 2 x bit L-1 of key y,
 *   plus 4 x bit L-1 of key z, so the voxels sorted by their interleaved (Morton) key come in
 *   the depth-first order the file lists them;
 * * every inner node is written as two bytes, two bits per child (children 0-3, then 4-7)
 *   holding 0 unknown, 1 free leaf, 2 occupied leaf or 3 inner node, followed by its inner
 *   children;
 * * pruning: a node (not the root) whose eight children all exist and are leaves of one state
 *   becomes a leaf of that state, bottom-up;
 * * the header's `size` counts the nodes of the pruned tree (root, inner nodes and leaves).
 */
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace keygrid::maps
{
class OctomapBinaryWriter
{
public:
	/** Key range per axis: keys 0 .. 65535, i.e. voxel index + 32768. */
	static constexpr int32_t kKeyOffset = 32768;

	/** Adds the voxel of (signed) voxel index (x, y, z): OctoMap key = index + 32768.
	 * Returns false (and adds nothing) when the index is outside the key range. A voxel added
	 * twice keeps the state of the last call (as OcTree::setNodeValue). */
	bool add(int32_t x, int32_t y, int32_t z, bool occupied);
	std::size_t voxels() const { return m_leaves.size(); }

	/** Writes the .bt file: OctoMap's header (first line, then `comment` as a '#' line when
	 * not empty, then the id / size / res keywords) and the binary tree. */
	void write(std::ostream& out, double resolution, const std::string& comment = {});

	/** The binary tree alone (what OcTree::writeBinaryData writes) and its node count. */
	std::string encodeTree(std::size_t& nodes);

private:
	/** Children code of the subtree of sorted leaves [begin, end) at `level` (0 = a voxel):
	 * 1 free leaf, 2 occupied leaf, 3 inner node (its bytes appended to out). */
	int encodeNode(std::size_t begin, std::size_t end, int level, std::string& out, std::size_t& nodes) const;

	/** Morton code of the key (3 bits per level, z y x from the top level down) shifted left by
	 * one, with the occupied state in bit 0. */
	std::vector<uint64_t> m_leaves;
};

}  // namespace keygrid::maps
