/** Keyframes without depth (monocular) in the maps: the 3D grid integrates a keyframe's map
 * points (one point straight ahead against the closed form), and a Sim(3) correction, which
 * gives each keyframe its own scale, leaves the 2D grid, the 3D grid and the floor estimate
 * as if they had been built from scratch with the corrected keyframes; so do map points
 * re-estimated by a final refinement. */
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <keygrid/maps/FloorFrameEstimator.h>
#include <keygrid/maps/KeyFrameMap.h>

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "ArchiveRoundTrip.h"
#include "Grid3DTestScenes.h"
#include "ISMSyntheticRoom.h"

using keygrid::CellState;
using keygrid::CISMOccupancyGrid2D;
using keygrid::CSubmappedOccupancyGrid3D;
using mrpt::math::TPoint3D;
using mrpt::poses::CPose3D;
namespace maps = keygrid::maps;

namespace
{
/** A monocular map of the synthetic room whose scale drifts: keyframe k sits at a drifted
 * rigid pose and holds its map points in map units 1 / s_k of the truth's (a point q in the
 * true camera frame is q / s_k in the keyframe's). The Sim(3) correction of keyframe k is the
 * true pose with scale s_k: afterwards the keyframe holds q again, at the true pose. */
struct ScaleDriftedRun
{
	std::vector<CPose3D> truth, drifted;
	std::vector<double> scales;
	std::vector<std::vector<TPoint3D>> seenTrue, seenDrifted;  // world points

	explicit ScaleDriftedRun(const keygrid::test::SyntheticRoom& room, std::size_t pointsPerKeyFrame = 400)
	{
		std::mt19937 rng(17);
		for (const auto& [x, y] : {std::pair{-0.8, 0.3}, std::pair{0.9, -0.4}})
			for (int k = 0; k < 12; k++) truth.push_back(room.cameraPose(x, y, 1.0, k * M_PI / 6, 15 * M_PI / 180));
		for (std::size_t k = 0; k < truth.size(); k++)
		{
			const CPose3D drift(0.02 * k, -0.01 * k, 0.005 * k, 0.5 * k * M_PI / 180, 0, 0);
			drifted.push_back(drift + truth[k]);
			scales.push_back(1.0 + 0.012 * k);  // the map shrank by up to a fifth along the run
			seenTrue.push_back(room.samplePoints(truth[k], pointsPerKeyFrame, 0.01, rng));
			std::vector<TPoint3D> d;
			for (const auto& p : seenTrue.back())
			{
				const TPoint3D q = truth[k].inverseComposePoint(p);
				d.push_back(drifted[k].composePoint(TPoint3D(q.x / scales[k], q.y / scales[k], q.z / scales[k])));
			}
			seenDrifted.push_back(d);
		}
	}

	maps::MapKeyFrame keyFrame(std::size_t k, bool corrected) const
	{
		maps::MapKeyFrame kf;
		kf.id = k;
		kf.T_world_cam = corrected ? truth[k] : drifted[k];
		kf.points_world = corrected ? seenTrue[k] : seenDrifted[k];
		kf.camera = keygrid::test::smallCamera();
		kf.travelled = 0.1 * k;
		return kf;
	}

	/** The Sim(3) correction of every keyframe; `withScales` false drops the scales (the maps
	 * as they were corrected before: new poses only). */
	maps::MapCorrection correction(bool withScales) const
	{
		maps::MapCorrection c;
		for (std::size_t k = 0; k < truth.size(); k++)
			c.poses[k] = keygrid::PoseCorrection{drifted[k], truth[k], withScales ? scales[k] : 1.0};
		return c;
	}
};

CISMOccupancyGrid2D roomGrid2D()
{
	CISMOccupancyGrid2D::TCreationOptions c;
	c.min_x = c.min_y = -2.5;
	c.max_x = c.max_y = 2.5;
	CISMOccupancyGrid2D grid(c);
	grid.insertionOptions.rangeNoise = maps::RangeNoiseModel::Constant;
	grid.setFloorFrame(CPose3D());  // the room's floor: z = 0
	return grid;
}

std::size_t differingCells(const CISMOccupancyGrid2D& a, const CISMOccupancyGrid2D& b)
{
	std::size_t n = 0;
	for (int cy = 0; cy < a.sizeY(); cy++)
		for (int cx = 0; cx < a.sizeX(); cx++)
			if (a.cellState(cx, cy) != b.cellState(cx, cy)) n++;
	return n;
}

/** Voxels known in either grid whose log-odds differ by more than 1e-4, and the known voxels
 * of `a`. */
std::pair<std::size_t, std::size_t> differingVoxels(const keygrid::VoxelBlockGrid& a, const keygrid::VoxelBlockGrid& b)
{
	std::size_t differ = 0, known = 0;
	a.forEachKnown([&](const keygrid::VoxelIndex& v, const keygrid::Voxel& x) {
		known++;
		const auto* y = b.find(v);
		if (!y || !y->isKnown() || std::abs(y->logOdds - x.logOdds) > 1e-4f) differ++;
	});
	b.forEachKnown([&](const keygrid::VoxelIndex& v, const keygrid::Voxel&) {
		const auto* x = a.find(v);
		if (!x || !x->isKnown()) differ++;
	});
	return {differ, known};
}
}  // namespace

/* One map point 1 m straight ahead of a camera whose centre is a voxel centre, looking along
 * +x: the ray crosses the voxels i = 0..19 of its row (free, one miss each), ends in voxel 20
 * (occupied, one hit) and marks nothing else. A world scaled by 2 puts the hit in voxel 40,
 * the old hit voxel on the free part of the ray. */
TEST(MapPointKeyFrames, OnePointStraightAheadFreesTheRayAndOccupiesItsEnd)
{
	CSubmappedOccupancyGrid3D grid;  // 5 cm
	grid.insertionOptions.integration.threads = 1;
	const auto& o = grid.insertionOptions.integration;
	const double c = 0.025;  // voxel centre
	const CPose3D T_world_cam = keygrid::test::SyntheticRoom().cameraPose(c, c, c, 0.0, 0.0);
	maps::MapKeyFrame kf;
	kf.id = 5;
	kf.T_world_cam = T_world_cam;
	kf.points_world = {TPoint3D(c + 1.0, c, c)};
	kf.camera = keygrid::test::smallCamera();
	maps::KeyFrameMap& map = grid;
	map.insertKeyFrame(kf, maps::KeyFrameFeed{});
	ASSERT_EQ(grid.keyframes().size(), 1u);
	EXPECT_TRUE(grid.keyframes().at(5).fromMapPoints);
	EXPECT_TRUE(grid.builtFromMapPoints());

	const auto expectRay = [&](int hit) {
		const auto g = grid.fusedGrid();
		std::size_t known = 0;
		g.forEachKnown([&](const keygrid::VoxelIndex& v, const keygrid::Voxel& x) {
			known++;
			EXPECT_EQ(v.y, 0);
			EXPECT_EQ(v.z, 0);
			EXPECT_GE(v.x, 0);
			EXPECT_LE(v.x, hit);
			EXPECT_FLOAT_EQ(x.logOdds, v.x == hit ? o.logOddsHit : o.logOddsMiss) << "voxel " << v.x;
		});
		EXPECT_EQ(known, static_cast<std::size_t>(hit + 1));
	};
	expectRay(20);

	maps::MapCorrection rescale;
	rescale.scale = 2.0;  // the camera kept where it was, its point twice as far
	rescale.poses[5] = {T_world_cam, keygrid::test::SyntheticRoom().cameraPose(c, c, c, 0.0, 0.0)};
	EXPECT_TRUE(map.applyCorrection(rescale));
	expectRay(40);
	EXPECT_NEAR(grid.keyframes().at(5).points_cam.front().z, 2.0, 1e-6);

	// A depth keyframe beside map points: the grid is no longer rebuilt from its points and,
	// like any grid of depth, refuses a scale.
	map.insertKeyFrame(
		[&] {
			maps::MapKeyFrame d = kf;
			d.id = 6;
			d.depth = keygrid::test::wallDepth(d.camera, 2.0f);
			return d;
		}(),
		maps::KeyFrameFeed{});
	EXPECT_FALSE(grid.builtFromMapPoints());
	EXPECT_THROW(map.applyCorrection(rescale), std::invalid_argument);
}

/* The 2D grid: a scale-drifted map corrected with each keyframe's similarity has the cells of
 * a grid built from the corrected keyframes (float round-off of the camera-frame storage
 * allowed); corrected with the poses alone, the rays keep their drifted lengths and it does
 * not. */
TEST(MapPointKeyFrames, A2DGridFollowsEachKeyFramesScale)
{
	keygrid::test::SyntheticRoom room;
	const ScaleDriftedRun run(room);
	CISMOccupancyGrid2D fresh = roomGrid2D(), corrected = roomGrid2D(), posesOnly = roomGrid2D();
	for (std::size_t k = 0; k < run.truth.size(); k++)
	{
		fresh.insertKeyFrame(run.keyFrame(k, true), maps::KeyFrameFeed{});
		corrected.insertKeyFrame(run.keyFrame(k, false), maps::KeyFrameFeed{});
		posesOnly.insertKeyFrame(run.keyFrame(k, false), maps::KeyFrameFeed{});
	}
	EXPECT_TRUE(corrected.applyCorrection(run.correction(true)));
	EXPECT_TRUE(posesOnly.applyCorrection(run.correction(false)));
	const std::size_t occupied = fresh.countStates()[2];
	ASSERT_GT(occupied, 300u);
	EXPECT_LE(differingCells(fresh, corrected), 5u);
	EXPECT_GT(differingCells(fresh, posesOnly), occupied / 4);

	maps::MapCorrection bad = run.correction(true);
	bad.poses[3].scale = 0.0;
	EXPECT_THROW(corrected.applyCorrection(bad), std::invalid_argument);
	EXPECT_LE(differingCells(fresh, corrected), 5u);  // refused before anything changed
}

/* The 3D grid of map points: the same, voxel by voxel (one submap after the correction, as in
 * the grid built from scratch), and a serialized copy keeps the points it is rebuilt from. */
TEST(MapPointKeyFrames, A3DGridOfMapPointsFollowsEachKeyFramesScale)
{
	keygrid::test::SyntheticRoom room;
	const ScaleDriftedRun run(room);
	CSubmappedOccupancyGrid3D fresh, corrected, posesOnly;
	for (auto* g : {&fresh, &corrected, &posesOnly}) g->insertionOptions.integration.threads = 2;
	for (std::size_t k = 0; k < run.truth.size(); k++)
	{
		fresh.insertKeyFrame(run.keyFrame(k, true), maps::KeyFrameFeed{});
		corrected.insertKeyFrame(run.keyFrame(k, false), maps::KeyFrameFeed{});
		posesOnly.insertKeyFrame(run.keyFrame(k, false), maps::KeyFrameFeed{});
	}
	ASSERT_EQ(fresh.numSubmaps(), 1u);

	// Serialized and read back before the correction: the stored points come back.
	CSubmappedOccupancyGrid3D restored = keygrid::test::archiveRoundTrip(corrected);
	ASSERT_EQ(restored.keyframes().size(), run.truth.size());
	EXPECT_TRUE(restored.builtFromMapPoints());

	EXPECT_TRUE(static_cast<maps::KeyFrameMap&>(corrected).applyCorrection(run.correction(true)));
	EXPECT_TRUE(static_cast<maps::KeyFrameMap&>(restored).applyCorrection(run.correction(true)));
	EXPECT_TRUE(static_cast<maps::KeyFrameMap&>(posesOnly).applyCorrection(run.correction(false)));
	EXPECT_EQ(corrected.numSubmaps(), 1u);
	const auto truthGrid = fresh.fusedGrid();
	const auto [differ, known] = differingVoxels(truthGrid, corrected.fusedGrid());
	ASSERT_GT(known, 20000u);
	EXPECT_LE(differ, known / 500) << differ << " of " << known;
	EXPECT_TRUE(restored.fusedGrid() == corrected.fusedGrid());
	EXPECT_GT(differingVoxels(truthGrid, posesOnly.fusedGrid()).first, known / 10);
	for (const auto& [id, rec] : corrected.keyframes()) EXPECT_TRUE(rec.T_world_cam == run.truth[id]);
}

/* A final refinement of a map without depth re-estimates the map points, not only the
 * keyframe poses: given with the correction (MapCorrection::points_world), they replace what
 * both grids hold of each keyframe. Here the inserted points are the scale-drifted ones and the
 * correction names the true poses without the scales, with the true points: both grids end as
 * if built from scratch with them, and without the points they do not. */
TEST(MapPointKeyFrames, ReEstimatedPointsReplaceTheInsertedOnes)
{
	keygrid::test::SyntheticRoom room;
	const ScaleDriftedRun run(room);
	maps::MapCorrection refined = run.correction(false);
	for (std::size_t k = 0; k < run.truth.size(); k++) refined.points_world[k] = run.seenTrue[k];
	refined.points_world[1000] = run.seenTrue[0];  // a keyframe the grids do not hold: ignored

	CISMOccupancyGrid2D fresh2d = roomGrid2D(), refined2d = roomGrid2D(), posesOnly2d = roomGrid2D();
	CSubmappedOccupancyGrid3D fresh3d, refined3d;
	for (auto* g : {&fresh3d, &refined3d}) g->insertionOptions.integration.threads = 2;
	for (std::size_t k = 0; k < run.truth.size(); k++)
	{
		fresh2d.insertKeyFrame(run.keyFrame(k, true), maps::KeyFrameFeed{});
		fresh3d.insertKeyFrame(run.keyFrame(k, true), maps::KeyFrameFeed{});
		for (maps::KeyFrameMap* g : std::initializer_list<maps::KeyFrameMap*>{&refined2d, &posesOnly2d, &refined3d})
			g->insertKeyFrame(run.keyFrame(k, false), maps::KeyFrameFeed{});
	}
	EXPECT_TRUE(refined2d.applyCorrection(refined));
	EXPECT_TRUE(posesOnly2d.applyCorrection(run.correction(false)));
	EXPECT_TRUE(static_cast<maps::KeyFrameMap&>(refined3d).applyCorrection(refined));

	const std::size_t occupied = fresh2d.countStates()[2];
	ASSERT_GT(occupied, 300u);
	EXPECT_EQ(differingCells(fresh2d, refined2d), 0u);
	EXPECT_GT(differingCells(fresh2d, posesOnly2d), occupied / 4);
	const auto [differ, known] = differingVoxels(fresh3d.fusedGrid(), refined3d.fusedGrid());
	ASSERT_GT(known, 20000u);
	EXPECT_LE(differ, known / 500) << differ << " of " << known;
}

/* The floor estimate on map points (monocular without a camera height) follows the scales
 * too: corrected, it finds the floor of the estimate made from the corrected samples. */
TEST(MapPointKeyFrames, TheFloorEstimateFollowsEachKeyFramesScale)
{
	keygrid::test::SyntheticRoom room;
	room.T_world_level = CPose3D(0.3, -0.2, 0.4, 0.2, 0.1, -0.05);
	const ScaleDriftedRun run(room, 1500);
	maps::FloorFrameEstimator fresh, corrected;
	const auto samples = [](const CPose3D& T, const std::vector<TPoint3D>& pts) {
		std::vector<mrpt::math::TPoint3Df> out;
		for (const auto& p : pts)
		{
			const auto q = T.inverseComposePoint(p);
			out.emplace_back(static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(q.z));
		}
		return out;
	};
	std::map<uint64_t, CPose3D> newPoses;
	std::map<uint64_t, double> scales;
	for (std::size_t k = 0; k < run.truth.size(); k++)
	{
		fresh.addKeyframe(k, run.truth[k], samples(run.truth[k], run.seenTrue[k]), 0.1 * k);
		corrected.addKeyframe(k, run.drifted[k], samples(run.drifted[k], run.seenDrifted[k]), 0.1 * k);
		newPoses[k] = run.truth[k];
		scales[k] = run.scales[k];
	}
	corrected.updatePoses(newPoses, scales);
	ASSERT_TRUE(fresh.T_world_floor().has_value());
	ASSERT_TRUE(corrected.T_world_floor().has_value());
	// The floor frame's z axis and height: the room's floor (z = 0 of the level frame).
	const CPose3D T_level_floor = *corrected.T_world_floor() - room.T_world_level;
	EXPECT_GT(T_level_floor.rotateVector(mrpt::math::TVector3D(0, 0, 1)).z, std::cos(0.5 * M_PI / 180));
	EXPECT_NEAR(T_level_floor.z(), 0.0, 0.01);
	EXPECT_NEAR((*corrected.T_world_floor() - *fresh.T_world_floor()).z(), 0.0, 0.005);
}
