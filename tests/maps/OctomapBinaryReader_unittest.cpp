/* The .bt reader against liboctomap's own files and against OctomapBinaryWriter: the voxels
 * read back are the voxels set (pruned cubes expanded), and the floor-frame comment line of a
 * keygrid-slam map gives back its pose. */
#include <keygrid/maps/ExportFrame.h>
#include <keygrid/maps/OctomapBinaryReader.h>
#include <keygrid/maps/OctomapBinaryWriter.h>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <fstream>
#include <map>
#include <random>

#include "TestData.h"

using keygrid::maps::OctomapBinaryVoxels;

namespace
{
using VoxelStates = std::map<OctomapBinaryVoxels::Index, bool>;

/** Two whole cubes (OctoMap prunes them to one leaf each) and scattered voxels of both states,
 * on both sides of zero. */
VoxelStates scene()
{
	VoxelStates v;
	for (int z = 0; z < 4; z++)
		for (int y = 0; y < 4; y++)
			for (int x = 0; x < 4; x++)
			{
				v[{x - 8, y + 4, z}] = false;
				v[{x + 16, y, z - 4}] = true;
			}
	std::mt19937 rng(7);
	std::uniform_int_distribution<int> pos(-30, 30), coin(0, 1);
	for (int i = 0; i < 500; i++) v[{pos(rng), pos(rng), pos(rng)}] = coin(rng) == 1;
	return v;
}

VoxelStates statesOf(const OctomapBinaryVoxels& r)
{
	VoxelStates s;
	for (const auto& i : r.occupied) EXPECT_TRUE(s.emplace(i, true).second);
	for (const auto& i : r.free) EXPECT_TRUE(s.emplace(i, false).second);
	return s;
}
}  // namespace

TEST(OctomapBinaryReader, ReadsTheVoxelsOfAnOctomapFile)
{
	const VoxelStates voxels = scene();
	octomap::OcTree tree(0.05);
	for (const auto& [i, occ] : voxels)
		tree.setNodeValue(
			octomap::OcTreeKey(octomap::key_type(i[0] + 32768), octomap::key_type(i[1] + 32768), octomap::key_type(i[2] + 32768)),
			occ ? 1.0f : -1.0f, true);
	tree.updateInnerOccupancy();
	tree.toMaxLikelihood();
	tree.prune();
	const std::string path = keygrid::test::scratchDir("octomap_reader") + "/octomap.bt";
	ASSERT_TRUE(tree.writeBinary(path));

	const auto r = keygrid::maps::readOctomapBinary(path);
	EXPECT_DOUBLE_EQ(r.resolution, 0.05);
	EXPECT_FALSE(r.T_world_floor.has_value());
	EXPECT_EQ(statesOf(r), voxels);
}

TEST(OctomapBinaryReader, ReadsBackTheWritersVoxelsAndFloorFrame)
{
	const VoxelStates voxels = scene();
	keygrid::maps::OctomapBinaryWriter w;
	for (const auto& [i, occ] : voxels) ASSERT_TRUE(w.add(i[0], i[1], i[2], occ));
	const mrpt::poses::CPose3D T_world_floor(0.3, 1.2, -0.2, 0.4, -1.1, 2.0);
	const std::string path = keygrid::test::scratchDir("octomap_reader_writer") + "/map_3d.bt";
	{
		std::ofstream f(path, std::ios::binary);
		w.write(f, 0.1, keygrid::maps::floorFrameComment(T_world_floor));
	}
	const auto r = keygrid::maps::readOctomapBinary(path);
	EXPECT_DOUBLE_EQ(r.resolution, 0.1);
	EXPECT_EQ(statesOf(r), voxels);
	ASSERT_TRUE(r.T_world_floor.has_value());
	EXPECT_NEAR((r.T_world_floor->asVectorVal() - T_world_floor.asVectorVal()).norm(), 0.0, 1e-7);
	ASSERT_FALSE(r.comments.empty());
	EXPECT_EQ(r.comments[0].rfind("keygrid T_world_floor", 0), 0u);
}

TEST(OctomapBinaryReader, BadFilesAreRefusedNamingTheFile)
{
	const std::string dir = keygrid::test::scratchDir("octomap_reader_bad");
	const auto expectThrow = [](const std::string& path, const std::string& what) {
		try
		{
			keygrid::maps::readOctomapBinary(path);
			ADD_FAILURE() << path << " was read";
		}
		catch (const std::runtime_error& e)
		{
			EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
		}
	};
	expectThrow(dir + "/missing.bt", "cannot read");
	std::ofstream(dir + "/text.bt") << "hello\n";
	expectThrow(dir + "/text.bt", "is not an OctoMap binary file");
	std::ofstream(dir + "/truncated.bt") << "# Octomap OcTree binary file\nid OcTree\nsize 9\nres 0.05\ndata\n\xff";
	expectThrow(dir + "/truncated.bt", "ends early");
	std::ofstream(dir + "/colour.bt") << "# Octomap OcTree binary file\nid ColorOcTree\nsize 0\nres 0.05\ndata\n";
	expectThrow(dir + "/colour.bt", "is not OcTree");
}

TEST(ExportFrame, TheFloorFrameCommentReadsBackFromEveryFileKind)
{
	const mrpt::poses::CPose3D T(1.5, -0.25, 0.125, 0.3, 0.2, -0.1);
	const std::string line = keygrid::maps::floorFrameComment(T);
	for (const char* marker : {"", "# ", "comment "})
	{
		const auto back = keygrid::maps::floorFrameFromComment(std::string(marker) + line);
		ASSERT_TRUE(back.has_value()) << marker;
		EXPECT_NEAR((back->asVectorVal() - T.asVectorVal()).norm(), 0.0, 1e-7) << marker;
	}
	EXPECT_FALSE(keygrid::maps::floorFrameFromComment("# keygrid T_world_floor (x y z qx qy qz qw): 1 2 3").has_value());
	EXPECT_FALSE(keygrid::maps::floorFrameFromComment("# something else: " + line).has_value());
}
