/** Grid morphing: identity correction = no change; a rigid correction moves the grid (exactly
 * for whole-voxel translations, within a voxel for rotations, quantified); submaps opened by a
 * conflict merge into one consistent grid with the closed-form weighted average; the
 * re-integration baseline equals a grid built at the corrected poses. */
#include "Grid3DTestScenes.h"

#include <gtest/gtest.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>

#include <set>

using namespace keygrid;
using mrpt::poses::CPose3D;

namespace
{
const mrpt::math::TPoint3D kRoomLo(-2, -1.5, -1), kRoomHi(2.5, 1.5, 3);

std::vector<CPose3D> roomPoses()
{
	// Optical frames (z forward) looking around the room from near its centre.
	return {CPose3D(0, 0, 0, 0, 0, 0), CPose3D(0.2, 0.1, 0.1, 0.5, 0.1, 0.0),
		CPose3D(0.4, -0.1, 0.3, 1.2, -0.1, 0.05), CPose3D(0.1, 0.0, 0.5, 2.0, 0.0, 0.1)};
}

/** A map of the room from roomPoses() transformed by T_corr, keyframe ids 10, 11, ... */
CSubmappedOccupancyGrid3D roomMap(const CPose3D& T_corr = {}, bool storeDepth = false)
{
	CSubmappedOccupancyGrid3D m(0.05);
	m.insertionOptions.storeKeyframeDepth = storeDepth;
	const auto cam = test::smallCamera(80, 60, 70);
	double travelled = 0;
	uint64_t id = 10;
	for (const auto& T : roomPoses())
	{
		const cv::Mat d = test::boxRoomDepth(cam, T, kRoomLo, kRoomHi);
		m.insertDepthFrame(d, cam, T_corr + T, travelled, id++);
		travelled += 0.2;
	}
	return m;
}

TrajectoryCorrection rigidCorrection(const CSubmappedOccupancyGrid3D& m, const CPose3D& T_corr)
{
	TrajectoryCorrection c;
	for (const auto& [id, k] : m.keyframes()) c[id] = {k.T_world_cam, T_corr + k.T_world_cam};
	return c;
}
}  // namespace

TEST(SubmappedMorphing, IdentityCorrectionLeavesTheGridUnchanged)
{
	auto m = roomMap();
	ASSERT_EQ(m.numSubmaps(), 1u);
	const VoxelBlockGrid before = m.submap(0).grid;
	const MorphingStats st = m.morphAndMergeSubmaps(rigidCorrection(m, CPose3D()));
	EXPECT_GT(st.morphedVoxels, before.numKnownVoxels() / 2);
	EXPECT_EQ(m.numSubmaps(), 1u);
	EXPECT_EQ(m.submap(0).grid.numKnownVoxels(), before.numKnownVoxels());
	EXPECT_TRUE(m.submap(0).grid == before);
}

TEST(SubmappedMorphing, WholeVoxelTranslationMovesEveryVoxelExactly)
{
	auto m = roomMap();
	const VoxelBlockGrid before = m.submap(0).grid;
	const CPose3D T_corr(0.25, 0.0, -0.10, 0, 0, 0);  // (+5, 0, -2) voxels
	m.morphAndMergeSubmaps(rigidCorrection(m, T_corr));
	const auto& after = m.submap(0).grid;
	EXPECT_EQ(after.numKnownVoxels(), before.numKnownVoxels());
	std::size_t mismatches = 0;
	before.forEachKnown([&](const VoxelIndex& v, const Voxel& x) {
		const Voxel* y = after.find({v.x + 5, v.y, v.z - 2});
		if (!y || !y->isKnown() || y->logOdds != x.logOdds || y->travelled != x.travelled) ++mismatches;
	});
	EXPECT_EQ(mismatches, 0u);
	EXPECT_NEAR(m.keyframes().at(10).T_world_cam.x(), 0.25, 1e-12);
}

TEST(SubmappedMorphing, RigidRotationMovesTheGridWithinAVoxel)
{
	auto m = roomMap();
	const VoxelBlockGrid before = m.submap(0).grid;
	const CPose3D T_corr(0.3, -0.2, 0.1, mrpt::DEG2RAD(10.0), mrpt::DEG2RAD(-4.0), mrpt::DEG2RAD(3.0));
	m.morphAndMergeSubmaps(rigidCorrection(m, T_corr));
	const auto& after = m.submap(0).grid;

	// Forward check: each occupied voxel's centre, moved by T_corr, lands in an occupied voxel
	// (exactly or in its 26-neighbourhood).
	auto occupiedNear = [](const VoxelBlockGrid& g, const VoxelIndex& c, int r) {
		for (int dz = -r; dz <= r; ++dz)
			for (int dy = -r; dy <= r; ++dy)
				for (int dx = -r; dx <= r; ++dx)
				{
					const Voxel* v = g.find({c.x + dx, c.y + dy, c.z + dz});
					if (v && v->isKnown() && v->logOdds > 0) return true;
				}
		return false;
	};
	std::size_t n = 0, exact = 0, near = 0;
	before.forEachKnown([&](const VoxelIndex& v, const Voxel& x) {
		if (x.logOdds <= 0) return;
		++n;
		const VoxelIndex t = after.voxelOf(T_corr.composePoint(before.centreOf(v)));
		exact += occupiedNear(after, t, 0) ? 1 : 0;
		near += occupiedNear(after, t, 1) ? 1 : 0;
	});
	ASSERT_GT(n, 1000u);
	const double exactShare = double(exact) / n, nearShare = double(near) / n;
	// Nearest-voxel resampling of a rotated grid: most land in the same voxel, all within one.
	EXPECT_GT(exactShare, 0.85) << exactShare;
	EXPECT_GT(nearShare, 0.999) << nearShare;
	// Backward check: no occupied voxel appears farther than one voxel from the moved surface.
	std::size_t m2 = 0, near2 = 0;
	const CPose3D inv = -T_corr;
	after.forEachKnown([&](const VoxelIndex& v, const Voxel& x) {
		if (x.logOdds <= 0) return;
		++m2;
		near2 += occupiedNear(before, before.voxelOf(inv.composePoint(after.centreOf(v))), 1) ? 1 : 0;
	});
	EXPECT_GT(double(near2) / m2, 0.999);
	EXPECT_NEAR(double(m2) / n, 1.0, 0.1);
	RecordProperty("exact_share", std::to_string(exactShare));
	RecordProperty("within_one_voxel_share", std::to_string(nearShare));
}

TEST(SubmappedMorphing, ConflictSubmapsMergeIntoOneConsistentGrid)
{
	CSubmappedOccupancyGrid3D m(0.05);
	m.insertionOptions.conflict.conflictMinVoxels = 100;
	const auto cam = test::smallCamera();
	m.insertDepthFrame(test::wallDepth(cam, 2.02f), cam, CPose3D(), 0.0, 1);
	m.insertDepthFrame(test::wallDepth(cam, 2.02f), cam, CPose3D(), 0.1, 2);
	const CPose3D drifted(0, 0, 0.5, 0, 0, 0);
	ASSERT_TRUE(m.insertDepthFrame(test::wallDepth(cam, 2.02f), cam, drifted, 5.0, 3).conflict);
	ASSERT_EQ(m.numSubmaps(), 2u);

	// Loop closure: keyframe 3 was really at the origin.
	TrajectoryCorrection c;
	c[3] = {drifted, CPose3D()};
	m.morphAndMergeSubmaps(c);
	ASSERT_EQ(m.numSubmaps(), 1u);
	const auto& g = m.submap(0).grid;
	std::size_t wall40 = 0, wall50 = 0;
	g.forEachKnown([&](const VoxelIndex& v, const Voxel& x) {
		if (x.logOdds <= 0) return;
		wall40 += v.z == 40;
		wall50 += v.z == 50;
	});
	EXPECT_EQ(wall50, 0u);  // the drifted copy of the wall is gone
	EXPECT_GT(wall40, 400u);
	// All three corrected cameras sit at the origin: equal weights, so the closed form is
	// the plain mean of (submap 0: 2 hits, 2 hits; submap 1 at z+0.5: 1 hit).
	const float hit = m.insertionOptions.integration.logOddsHit;
	const float miss = m.insertionOptions.integration.logOddsMiss;
	EXPECT_NEAR(g.find({0, 0, 40})->logOdds, (2 * hit + 2 * hit + hit) / 3.0, 1e-5);
	// z = 1.525 m: free twice in submap 0, and (at z = 2.025 m) free once in submap 1.
	EXPECT_NEAR(g.find({0, 0, 30})->logOdds, (2 * miss + 2 * miss + miss) / 3.0, 1e-5);
	EXPECT_EQ(m.keyframes().at(3).submap, 0u);
	EXPECT_NEAR(m.keyframes().at(3).T_world_cam.z(), 0.0, 1e-12);
}

TEST(SubmappedMorphing, ReintegrationBaselineEqualsBuildingAtCorrectedPoses)
{
	const CPose3D T_corr(0.1, 0.05, -0.02, 0.1, 0.0, 0.0);
	auto m = roomMap(CPose3D(), true);
	m.reintegrateAtCorrectedPoses(rigidCorrection(m, T_corr));
	const auto direct = roomMap(T_corr);
	EXPECT_TRUE(m.submap(0).grid == direct.submap(0).grid);

	auto noDepth = roomMap();
	EXPECT_THROW(noDepth.reintegrateAtCorrectedPoses({}), std::logic_error);
}

TEST(SubmappedMorphing, TravelWindowFollowsTheKeyframeThatPlacedTheContent)
{
	// Keyframe 1 (travelled 0) and keyframe 2 (travelled 1.0 m) see the same wall from the same
	// pose; every voxel was last updated by keyframe 2. Only keyframe 1 is corrected (+0.25 m
	// along z): its correction must not drag keyframe 2's content.
	const auto cam = test::smallCamera();
	auto build = [&](double window) {
		CSubmappedOccupancyGrid3D m(0.05);
		m.morphingOptions.travelWindow = window;
		m.insertDepthFrame(test::wallDepth(cam, 2.02f), cam, CPose3D(), 0.0, 1);
		m.insertDepthFrame(test::wallDepth(cam, 2.02f), cam, CPose3D(), 1.0, 2);
		TrajectoryCorrection c;
		c[1] = {CPose3D(), CPose3D(0, 0, 0.25, 0, 0, 0)};
		m.morphAndMergeSubmaps(c);
		return m;
	};
	const float hit = DepthIntegrationOptions().logOddsHit;
	const auto strict = build(0.3);
	EXPECT_FLOAT_EQ(strict.submap(0).grid.find({0, 0, 40})->logOdds, 2 * hit);
	const Voxel* moved = strict.submap(0).grid.find({0, 0, 45});
	EXPECT_TRUE(!moved || !moved->isKnown() || moved->logOdds <= 0);
	// Without the window keyframe 1's lookup (0.25 m closer: a free voxel) is averaged in.
	const auto off = build(0.0);
	EXPECT_LT(off.submap(0).grid.find({0, 0, 40})->logOdds, 2 * hit);
}
