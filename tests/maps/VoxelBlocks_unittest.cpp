/** Sparse block storage: indexing (also negative), allocation, copies, memory accounting. */
#include <gtest/gtest.h>
#include <keygrid/maps/VoxelBlockGrid.h>

using keygrid::Voxel;
using keygrid::VoxelBlock;
using keygrid::VoxelBlockGrid;
using keygrid::VoxelIndex;

TEST(VoxelBlocks, IndexingMatchesFloorDivision)
{
	VoxelBlockGrid g(0.05);
	for (int x = -20; x <= 20; ++x)
	{
		const VoxelIndex v{x, -x, 3 * x};
		const VoxelIndex b = VoxelBlockGrid::blockOf(v);
		// floor division by 8, also for negative indices
		EXPECT_EQ(b.x, static_cast<int>(std::floor(x / 8.0)));
		EXPECT_EQ(b.y, static_cast<int>(std::floor(-x / 8.0)));
		EXPECT_EQ(b.z, static_cast<int>(std::floor(3 * x / 8.0)));
		const VoxelIndex f = VoxelBlockGrid::firstVoxelOf(b);
		const int l = VoxelBlockGrid::localLinear(v);
		EXPECT_EQ(l, VoxelBlock::linear(v.x - f.x, v.y - f.y, v.z - f.z));
	}
	EXPECT_EQ(g.voxelOf({-0.001, 0.0, 0.049}), (VoxelIndex{-1, 0, 0}));
	const auto c = g.centreOf({-1, 0, 2});
	EXPECT_DOUBLE_EQ(c.x, -0.025);
	EXPECT_DOUBLE_EQ(c.z, 0.125);
}

TEST(VoxelBlocks, AllocationFindAndCounts)
{
	VoxelBlockGrid g(0.1);
	EXPECT_EQ(g.find({0, 0, 0}), nullptr);
	g.at({-1, -1, -1}) = Voxel{2.0f, 1.5f};
	g.at({7, 0, 0}) = Voxel{-1.0f, 0.5f};  // same block as (0,0,0)
	g.at({8, 0, 0}) = Voxel{0.5f, 0.0f};  // next block
	EXPECT_EQ(g.numBlocks(), 3u);
	EXPECT_EQ(g.numAllocatedVoxels(), 3u * 512u);
	EXPECT_EQ(g.numKnownVoxels(), 3u);
	EXPECT_EQ(g.numOccupiedVoxels(), 2u);
	ASSERT_NE(g.find({0, 0, 0}), nullptr);  // allocated, unknown
	EXPECT_FALSE(g.find({0, 0, 0})->isKnown());
	EXPECT_FLOAT_EQ(g.find({-1, -1, -1})->travelled, 1.5f);

	std::size_t n = 0;
	g.forEachKnown([&](const VoxelIndex& v, const Voxel& vx) {
		++n;
		if (v == VoxelIndex{8, 0, 0})
		{
			EXPECT_FLOAT_EQ(vx.logOdds, 0.5f);
		}
	});
	EXPECT_EQ(n, 3u);

	// 8 bytes per voxel plus the hash-map overhead, divided over 512 voxels per block.
	EXPECT_EQ(sizeof(Voxel), 8u);
	EXPECT_GT(g.bytesPerAllocatedVoxel(), 8.0);
	EXPECT_LT(g.bytesPerAllocatedVoxel(), 8.5);
}

TEST(VoxelBlocks, CopyIsDeepAndEqualityIgnoresUnknownBlocks)
{
	VoxelBlockGrid a(0.05);
	a.at({1, 2, 3}) = Voxel{1.0f, 2.0f};
	VoxelBlockGrid b = a;
	EXPECT_TRUE(a == b);
	b.at({1, 2, 3}).logOdds = 1.5f;
	EXPECT_FLOAT_EQ(a.find({1, 2, 3})->logOdds, 1.0f);
	EXPECT_FALSE(a == b);
	VoxelBlockGrid c = a;
	c.blockAt({100, 100, 100});  // an allocated block of unknown voxels changes nothing
	EXPECT_TRUE(a == c);
	EXPECT_THROW(VoxelBlockGrid(0.0), std::invalid_argument);
}
