/** Grid morphing: identity correction = no change; a rigid correction moves the grid (exactly
 * for whole-voxel translations, within a voxel for rotations, quantified); submaps opened by a
 * conflict merge into one consistent grid with the closed-form weighted average; the
 * re-integration baseline equals a grid built at the corrected poses. */
#include "Grid3DTestScenes.h"

#include <gtest/gtest.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <cmath>
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
	auto m = test::mapOfWall();
	const auto cam = test::smallCamera();
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

namespace
{
/** The room map with a different correction per keyframe (a non-rigid trajectory correction,
 * so every keyframe maps voxels to other earlier positions), as morphAndMerge input. */
struct NonRigidCase
{
	CSubmappedOccupancyGrid3D map = roomMap();
	std::vector<MorphKeyframe> keyframes;

	NonRigidCase()
	{
		int i = 0;
		for (const auto& [id, k] : map.keyframes())
		{
			const CPose3D corr(0.03 * i, -0.02 * i, 0.017 * i, mrpt::DEG2RAD(1.5 * i), mrpt::DEG2RAD(-0.7 * i), 0);
			keyframes.push_back(CSubmappedOccupancyGrid3D::morphKeyframe(id, k, corr + k.T_world_cam));
			++i;
		}
	}
	VoxelBlockGrid morph(const MorphingOptions& o, MorphingStats* st = nullptr) const
	{
		return morphAndMerge({&map.submap(0).grid}, keyframes, o, st);
	}
};
}  // namespace

namespace
{
/** Independent implementation of the definition in GridMorphing.h (every keyframe, per-voxel
 * cone test through insideViewCone, trilinear lookup, travel window (0 = off), w = 1 / max(z,
 * zMin)^2), evaluated on every voxel of the morphed grid: the culling and pruning of
 * morphAndMerge must not change any value the definition gives. */
void expectTheBruteForceWeightedAverage(const NonRigidCase& c, const MorphingOptions& o)
{
	const VoxelBlockGrid& src = c.map.submap(0).grid;
	MorphingStats st;
	const VoxelBlockGrid out = c.morph(o, &st);
	const double res = src.resolution();
	std::size_t checked = 0, mismatches = 0;
	out.forEachKnown([&](const VoxelIndex& vi, const Voxel& v) {
		const auto X = out.centreOf(vi);
		double sw = 0, swl = 0;
		for (const auto& k : c.keyframes)
		{
			if (!insideViewCone(X, k.T_world_cam_new, k.camera, o.viewConeMaxRange)) continue;
			const auto P = k.T_world_cam_old.composePoint(k.T_world_cam_new.inverseComposePoint(X));
			const double q[3] = {P.x / res - 0.5, P.y / res - 0.5, P.z / res - 0.5};
			int i0[3];
			double f[3];
			for (int a = 0; a < 3; ++a)
			{
				const double r = std::round(q[a]);
				const double qs = std::abs(q[a] - r) < 1e-6 ? r : q[a];
				i0[a] = static_cast<int>(std::floor(qs));
				f[a] = qs - i0[a];
			}
			double cw = 0, cl = 0;
			for (int corner = 0; corner < 8; ++corner)
			{
				const int d[3] = {corner & 1, (corner >> 1) & 1, (corner >> 2) & 1};
				double t = 1;
				for (int a = 0; a < 3; ++a) t *= d[a] ? f[a] : 1 - f[a];
				const Voxel* s = src.find({i0[0] + d[0], i0[1] + d[1], i0[2] + d[2]});
				if (t <= 0 || !s || !s->isKnown()) continue;
				if (o.travelWindow > 0 && std::abs(s->travelled - k.travelled) > o.travelWindow) continue;
				cw += t;
				cl += t * s->logOdds;
			}
			if (cw < 0.5) continue;
			const double z2 = std::pow(X.x - k.T_world_cam_new.x(), 2) +
				std::pow(X.y - k.T_world_cam_new.y(), 2) + std::pow(X.z - k.T_world_cam_new.z(), 2);
			const double w = 1.0 / std::max(z2, o.minWeightDistance * o.minWeightDistance);
			sw += w;
			swl += w * cl / cw;
		}
		if (sw <= 0) return;  // carried or outside every cone: not defined by the average
		++checked;
		if (std::abs(v.logOdds - swl / sw) > 1e-4) ++mismatches;
	});
	ASSERT_GT(checked, 5000u);
	EXPECT_EQ(checked, st.morphedVoxels);
	// Voxel centres exactly on a cone boundary may be decided differently (pixel vs plane test).
	EXPECT_LE(mismatches, checked / 1000) << mismatches << " of " << checked;
	::testing::Test::RecordProperty("brute_force_checked", std::to_string(checked));
	::testing::Test::RecordProperty("brute_force_mismatches", std::to_string(mismatches));
}
}  // namespace

TEST(SubmappedMorphing, MatchesABruteForceWeightedAverage)
{
	expectTheBruteForceWeightedAverage(NonRigidCase(), MorphingOptions());
}

TEST(SubmappedMorphing, MatchesABruteForceWeightedAverageWithoutTravelWindow)
{
	// Window off: every known source voxel counts (the per-block voxel masks hold all of them).
	MorphingOptions o;
	o.travelWindow = 0;
	expectTheBruteForceWeightedAverage(NonRigidCase(), o);
}

TEST(SubmappedMorphing, KeyframeLimitAboveTheKeyframeCountChangesNothing)
{
	const NonRigidCase c;
	MorphingOptions o;
	MorphingStats all, large, one;
	const VoxelBlockGrid exact = c.morph(o, &all);
	o.maxKeyframesPerBlock = 1000;
	EXPECT_TRUE(c.morph(o, &large) == exact);
	EXPECT_EQ(large.lookups, all.lookups);
	// One keyframe per block: fewer lookups, a different (approximate) grid.
	o.maxKeyframesPerBlock = 1;
	const VoxelBlockGrid approx = c.morph(o, &one);
	EXPECT_LT(one.lookups, all.lookups);
	EXPECT_LE(one.blockKeyframePairs, one.evaluatedVoxels / VoxelBlock::kVoxels);
	EXPECT_FALSE(approx == exact);
}

TEST(SubmappedMorphing, ResultDoesNotDependOnTheThreadCount)
{
	const NonRigidCase c;
	MorphingOptions o;
	o.threads = 1;
	const VoxelBlockGrid one = c.morph(o);
	for (unsigned t : {2u, 3u, 5u})
	{
		o.threads = t;
		EXPECT_TRUE(c.morph(o) == one) << t << " threads";
	}
	o.maxKeyframesPerBlock = 2;
	o.threads = 1;
	const VoxelBlockGrid limited = c.morph(o);
	o.threads = 3;
	EXPECT_TRUE(c.morph(o) == limited);
}

TEST(SubmappedMorphing, KeyframeLimitIniRoundTripAndValidation)
{
	const std::string sec = "morph";
	MorphingOptions o;
	EXPECT_EQ(o.maxKeyframesPerBlock, 0u);
	mrpt::config::CConfigFileMemory cfg(std::string("[morph]\nmorphMaxKeyframesPerBlock = 12\n"));
	o.loadFromConfigFile(cfg, sec);
	EXPECT_EQ(o.maxKeyframesPerBlock, 12u);
	mrpt::config::CConfigFileMemory saved;
	o.saveToConfigFile(saved, sec);
	MorphingOptions back;
	back.loadFromConfigFile(mrpt::config::CConfigFileMemory(saved.getContent()), sec);  // through the INI text
	EXPECT_EQ(back.maxKeyframesPerBlock, 12u);
	for (const char* bad : {"-1", "2.5", "abc"})
	{
		mrpt::config::CConfigFileMemory b(std::string("[morph]\nmorphMaxKeyframesPerBlock = ") + bad + "\n");
		MorphingOptions x;
		try
		{
			x.loadFromConfigFile(b, sec);
			ADD_FAILURE() << bad << " must throw";
		}
		catch (const std::invalid_argument& e)
		{
			EXPECT_NE(std::string(e.what()).find("morphMaxKeyframesPerBlock"), std::string::npos) << e.what();
		}
	}
}
