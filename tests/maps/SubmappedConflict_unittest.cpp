/** Travelled-distance bookkeeping, the exploration / localization machine and conflicts that
 * open submaps. */
#include "Grid3DTestScenes.h"

#include <gtest/gtest.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>

using namespace keygrid;
using mrpt::poses::CPose3D;
using test::mapOfWall;

TEST(SubmappedConflict, VoxelsRememberTheTravelledDistanceOfTheirLastUpdate)
{
	auto m = mapOfWall();
	const auto cam = test::smallCamera();
	// A camera 2 m to the right sees only part of the wall: x in [0.92, 3.08] m at z = 2.02 m.
	const auto r = m.insertDepthFrame(test::wallDepth(cam, 2.02f), cam, CPose3D(2.0, 0, 0, 0, 0, 0), 1.0, 3);
	EXPECT_FALSE(r.conflict);
	const auto& g = m.submap(0).grid;
	EXPECT_FLOAT_EQ(g.find({0, 0, 40})->travelled, 0.1f);  // x in [0, 0.05): not seen again
	EXPECT_FLOAT_EQ(g.find({40, 0, 40})->travelled, 1.0f);  // x in [2.0, 2.05): observed
	EXPECT_FLOAT_EQ(g.find({20, 0, 40})->travelled, 1.0f);  // x in [1.0, 1.05): re-observed
	EXPECT_FLOAT_EQ(g.find({20, 0, 40})->logOdds, 3 * m.insertionOptions.integration.logOddsHit);
	EXPECT_FLOAT_EQ(g.find({40, 0, 40})->logOdds, m.insertionOptions.integration.logOddsHit);
	ASSERT_EQ(m.keyframes().size(), 3u);
	EXPECT_DOUBLE_EQ(m.keyframes().at(3).travelled, 1.0);
	EXPECT_DOUBLE_EQ(m.keyframes().at(3).T_world_cam.x(), 2.0);
	EXPECT_THROW(m.insertDepthFrame(test::wallDepth(cam, 2.0f), cam, CPose3D(), 1.1, 3), std::invalid_argument);
}

TEST(SubmappedConflict, DriftCarvingOldConfidentVoxelsOpensASubmap)
{
	auto m = mapOfWall();
	// Re-observing what was mapped 0.1 m of travel ago is not a revisit.
	EXPECT_EQ(m.mode(), MappingMode::Exploration);
	const VoxelBlockGrid before = m.submap(0).grid;
	const auto cam = test::smallCamera();
	// Drifted pose: the camera believes it is 0.5 m further forward, so the wall lands at 2.52 m
	// and the rays carve the old wall, last updated 4.9 m of travel ago.
	const auto r = m.insertDepthFrame(test::wallDepth(cam, 2.02f), cam, CPose3D(0, 0, 0.5, 0, 0, 0), 5.0, 3);
	EXPECT_TRUE(r.conflict) << r.reason;
	EXPECT_EQ(r.mode, MappingMode::Exploration);
	EXPECT_GE(r.evidence.staleContradictions, 100u);
	EXPECT_EQ(r.evidence.hitsOnOccupied, 0u);
	ASSERT_EQ(m.numSubmaps(), 2u);
	EXPECT_EQ(m.activeSubmap(), 1u);
	EXPECT_EQ(m.submap(1).anchorKeyframe, 3u);
	EXPECT_EQ(m.submap(1).keyframes, std::vector<uint64_t>{3});
	EXPECT_EQ(m.submap(0).keyframes, (std::vector<uint64_t>{1, 2}));
	EXPECT_EQ(m.keyframes().at(3).submap, 1u);
	EXPECT_TRUE(m.submap(0).grid == before);  // the old submap was protected
	EXPECT_EQ(m.submap(1).grid.find({0, 0, 50})->logOdds, m.insertionOptions.integration.logOddsHit);
}

TEST(SubmappedConflict, NoConflictWhenTheVoxelsAreRecentOrInLocalization)
{
	const auto cam = test::smallCamera();
	{
		auto m = mapOfWall();
		// Same carving, but the voxels were updated only 0.2 m of travel ago: not stale.
		const auto r = m.insertDepthFrame(test::wallDepth(cam, 2.02f), cam, CPose3D(0, 0, 0.5, 0, 0, 0), 0.3, 3);
		EXPECT_FALSE(r.conflict);
		EXPECT_EQ(r.evidence.staleContradictions, 0u);
		EXPECT_GE(r.evidence.contradictions, 100u);
		EXPECT_EQ(m.numSubmaps(), 1u);
	}
	{
		auto m = mapOfWall();
		m.notifyLoopClosure();  // localization: no conflict detection
		const auto r = m.insertDepthFrame(test::wallDepth(cam, 2.02f), cam, CPose3D(0, 0, 0.5, 0, 0, 0), 5.0, 3);
		EXPECT_FALSE(r.conflict);
		EXPECT_EQ(r.mode, MappingMode::Localization);
		EXPECT_GE(r.evidence.staleContradictions, 100u);
		EXPECT_EQ(m.numSubmaps(), 1u);
	}
}

TEST(SubmappedConflict, ModeMachineTransitions)
{
	ConflictOptions o;
	MappingModeMachine mm(o);
	FrameEvidence ev;
	ev.updated = 1000;
	ev.hits = 100;
	ev.known = 500;
	ev.hitsOnOccupied = 90;
	ev.hitsOnStaleOccupied = 10;  // 0.1 < enter 0.2: recently mapped content does not count
	EXPECT_EQ(mm.step(ev).mode, MappingMode::Exploration);
	ev.hitsOnStaleOccupied = 30;  // 0.3 >= enter 0.2
	ev.stale = 200;
	ev.staleContradictions = 5;  // inconsistent revisit: 0.05 > 0.02, stays in exploration
	EXPECT_EQ(mm.step(ev).mode, MappingMode::Exploration);
	ev.staleContradictions = 1;  // 0.01 <= 0.02: consistent
	EXPECT_EQ(mm.step(ev).mode, MappingMode::Localization);
	ev.hitsOnStaleOccupied = 0;  // the old voxels were refreshed: stays while hits are on the map
	ev.hitsOnOccupied = 30;  // 0.3 >= exit 0.25
	EXPECT_EQ(mm.step(ev).mode, MappingMode::Localization);
	ev.hitsOnOccupied = 20;  // 0.2 < exit: new territory
	EXPECT_EQ(mm.step(ev).mode, MappingMode::Exploration);
	// Conflict needs both the count and the share of the hits.
	ev.stale = 10000;
	ev.hits = 10000;
	ev.staleContradictions = 400;  // >= 300 but 0.04 of the hits < 0.05
	EXPECT_FALSE(mm.step(ev).conflict);
	ev.hits = 2000;  // 0.2
	const auto d = mm.step(ev);
	EXPECT_TRUE(d.conflict);
	EXPECT_FALSE(d.reason.empty());
	mm.notifyRevisit();
	const auto d2 = mm.step(ev);
	EXPECT_EQ(d2.mode, MappingMode::Localization);
	EXPECT_FALSE(d2.conflict);

	ConflictOptions bad;
	bad.localizationExitHitFraction = 1.5;
	EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(SubmappedConflict, ConsistentRevisitEntersLocalization)
{
	// The wall mapped at travelled 0 / 0.1 is seen again, from the right pose, after 5 m.
	auto m = mapOfWall();
	const auto cam = test::smallCamera();
	const auto r = m.insertDepthFrame(test::wallDepth(cam, 2.02f), cam, CPose3D(), 5.0, 3);
	EXPECT_EQ(r.mode, MappingMode::Localization) << r.reason;
	EXPECT_FALSE(r.conflict);
	EXPECT_GT(r.evidence.revisitHitFraction(), 0.99);
	EXPECT_EQ(r.evidence.staleContradictions, 0u);
}
