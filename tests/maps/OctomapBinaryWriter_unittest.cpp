/* The .bt writer against liboctomap itself: the same voxels set in an octomap::OcTree, made
 * maximum-likelihood, pruned and written by OctoMap give the same bytes. */
#include <keygrid/maps/OctomapBinaryWriter.h>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <map>
#include <random>
#include <sstream>
#include <tuple>
#include <vector>

namespace
{
using keygrid::maps::OctomapBinaryWriter;
using OctreeVoxel = std::tuple<int, int, int, bool>;

/** What OctoMap writes for the voxels (set in this order at full depth). */
std::string octomapBytes(const std::vector<OctreeVoxel>& voxels, double res, const std::string& comment)
{
	octomap::OcTree tree(res);
	for (const auto& [x, y, z, occ] : voxels)
	{
		const octomap::OcTreeKey key(static_cast<octomap::key_type>(x + 32768), static_cast<octomap::key_type>(y + 32768),
			static_cast<octomap::key_type>(z + 32768));
		tree.setNodeValue(key, occ ? 1.0f : -1.0f, true);
	}
	tree.updateInnerOccupancy();
	tree.toMaxLikelihood();
	tree.prune();
	std::ostringstream s;
	s << "# Octomap OcTree binary file\n";
	if (!comment.empty()) s << "# " << comment << "\n";
	s << "# (feel free to add / change comments, but leave the first line as it is!)\n#\n"
	  << "id " << tree.getTreeType() << "\nsize " << tree.size() << "\nres " << tree.getResolution() << "\ndata\n";
	tree.writeBinaryData(s);
	return s.str();
}

std::string writerBytes(const std::vector<OctreeVoxel>& voxels, double res, const std::string& comment)
{
	OctomapBinaryWriter w;
	for (const auto& [x, y, z, occ] : voxels) EXPECT_TRUE(w.add(x, y, z, occ));
	std::ostringstream s;
	w.write(s, res, comment);
	return s.str();
}

/** Whole cubes of one state (pruned at several levels), cubes with one voxel flipped or
 * missing (not pruned), scattered voxels on both sides of zero, and repeated voxels. */
std::vector<OctreeVoxel> mixedScene(unsigned seed)
{
	std::mt19937 rng(seed);
	std::uniform_int_distribution<int> pos(-40, 40), coin(0, 1), sizeLog(1, 3);
	std::vector<OctreeVoxel> v;
	for (int c = 0; c < 12; c++)
	{
		const int n = 1 << sizeLog(rng);
		// Aligned to the cube size, as OctoMap's nodes are.
		const int x0 = pos(rng) / n * n, y0 = pos(rng) / n * n, z0 = pos(rng) / n * n;
		const bool occ = coin(rng) == 1;
		const int defect = c % 3;  // 0 whole, 1 one voxel flipped, 2 one voxel missing
		for (int z = 0; z < n; z++)
			for (int y = 0; y < n; y++)
				for (int x = 0; x < n; x++)
				{
					const bool first = x == 0 && y == 0 && z == 0;
					if (first && defect == 2) continue;
					v.emplace_back(x0 + x, y0 + y, z0 + z, first && defect == 1 ? !occ : occ);
				}
	}
	for (int i = 0; i < 3000; i++) v.emplace_back(pos(rng), pos(rng), pos(rng), coin(rng) == 1);
	for (int i = 0; i < 200; i++)
	{
		auto again = v[static_cast<std::size_t>(i * 7)];
		std::get<3>(again) = !std::get<3>(again);  // the later state wins
		v.push_back(again);
	}
	return v;
}
}  // namespace

TEST(OctomapBinaryWriter, SameBytesAsOctomapOnMixedScenes)
{
	for (unsigned seed = 1; seed <= 4; seed++)
	{
		const auto voxels = mixedScene(seed);
		EXPECT_EQ(writerBytes(voxels, 0.05, "keygrid T_world_floor: test"), octomapBytes(voxels, 0.05, "keygrid T_world_floor: test"))
			<< "seed " << seed;
	}
}

TEST(OctomapBinaryWriter, KeysAroundTheOriginAndAtTheRangeEdges)
{
	// The 2x2x2 block around the origin lies in the root's eight children, one voxel each
	// (keys 32767 and 32768 differ in their top bit): eight paths of single children.
	std::vector<OctreeVoxel> v;
	for (int z = -1; z <= 0; z++)
		for (int y = -1; y <= 0; y++)
			for (int x = -1; x <= 0; x++) v.emplace_back(x, y, z, false);
	v.emplace_back(-32768, 32767, 0, true);
	v.emplace_back(32767, -32768, -32768, false);
	EXPECT_EQ(writerBytes(v, 0.1, ""), octomapBytes(v, 0.1, ""));
	// One aligned 2x2x2 block of free voxels: collapses into one leaf.
	std::vector<OctreeVoxel> octant(v.begin(), v.begin() + 8);
	for (auto& [x, y, z, occ] : octant) x += 2, y += 2, z += 2;
	EXPECT_EQ(writerBytes(octant, 0.1, ""), octomapBytes(octant, 0.1, ""));
	EXPECT_EQ(writerBytes({}, 0.1, ""), octomapBytes({}, 0.1, ""));

	OctomapBinaryWriter w;
	EXPECT_FALSE(w.add(32768, 0, 0, true));
	EXPECT_FALSE(w.add(0, -32769, 0, true));
	EXPECT_EQ(w.voxels(), 0u);
}

TEST(OctomapBinaryWriter, OctomapReadsTheVoxelStatesBack)
{
	const auto voxels = mixedScene(9);
	std::istringstream in(writerBytes(voxels, 0.05, "a comment"));
	octomap::OcTree read(1.0);
	ASSERT_TRUE(read.readBinary(in));
	const octomap::OcTree* tree = &read;
	EXPECT_DOUBLE_EQ(tree->getResolution(), 0.05);
	std::map<std::tuple<int, int, int>, bool> last;
	for (const auto& [x, y, z, occ] : voxels) last[{x, y, z}] = occ;
	for (const auto& [k, occ] : last)
	{
		const auto [x, y, z] = k;
		const octomap::OcTreeNode* n = tree->search(octomap::OcTreeKey(x + 32768, y + 32768, z + 32768));
		ASSERT_TRUE(n != nullptr) << x << " " << y << " " << z;
		EXPECT_EQ(tree->isNodeOccupied(n), occ) << x << " " << y << " " << z;
	}
}
