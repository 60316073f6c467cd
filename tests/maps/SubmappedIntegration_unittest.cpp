/** Depth-frame integration: a synthetic wall gives occupied voxels exactly where the rays end
 * and free voxels before it; one update per voxel per frame; occupied wins; max range;
 * deterministic with any thread count; the sparse path equals the dense one. */
#include "Grid3DTestScenes.h"

#include <gtest/gtest.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <keygrid/maps/DepthFrameIntegrator.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <set>

using namespace keygrid;

namespace
{
constexpr double kRes = 0.05;

VoxelBlockGrid integrateWall(const DepthIntegrationOptions& o, float z, const mrpt::poses::CPose3D& T = {})
{
	DepthFrameIntegrator integ(o);
	VoxelBlockGrid g(kRes);
	const auto cam = test::smallCamera();
	integ.apply(g, integ.castFrame(test::wallDepth(cam, z), cam, T, kRes), 1.0);
	return g;
}
}  // namespace

class SubmappedIntegrationModes : public ::testing::TestWithParam<bool>
{
};
INSTANTIATE_TEST_SUITE_P(RayPerPixelOrPerEndVoxel, SubmappedIntegrationModes, ::testing::Bool());

TEST_P(SubmappedIntegrationModes, WallGivesOccupiedVoxelsAtTheRayEndsAndFreeBefore)
{
	DepthIntegrationOptions o;
	o.discretizeEndpoints = GetParam();
	const float z = 2.02f;
	const auto cam = test::smallCamera();
	const VoxelBlockGrid g = integrateWall(o, z);
	{
		DepthFrameIntegrator integ(o);
		const auto upd = integ.castFrame(test::wallDepth(cam, z), cam, {}, kRes);
		EXPECT_EQ(upd.rays, 64u * 48u);
		EXPECT_EQ(upd.castRays, GetParam() ? upd.hitVoxels : upd.rays);
	}

	// Closed form: the voxels holding the pixel-centre points (u-cx)/f*z, (v-cy)/f*z, z.
	std::set<VoxelIndex> expected;
	for (unsigned v = 0; v < cam.height; ++v)
		for (unsigned u = 0; u < cam.width; ++u)
			expected.insert(g.voxelOf({(u - cam.cx) / cam.fx * z, (v - cam.cy) / cam.fy * z, z}));
	std::set<VoxelIndex> occupied;
	std::size_t freeCount = 0;
	g.forEachKnown([&](const VoxelIndex& vi, const Voxel& v) {
		if (v.logOdds > 0) occupied.insert(vi);
		else ++freeCount;
		// one update per voxel in one frame: exactly one hit or one miss
		EXPECT_TRUE(v.logOdds == o.logOddsHit || v.logOdds == o.logOddsMiss) << v.logOdds;
		EXPECT_FLOAT_EQ(v.travelled, 1.0f);
	});
	EXPECT_EQ(occupied, expected);
	for (const auto& vi : occupied) EXPECT_EQ(vi.z, 40);  // floor(2.02 / 0.05)
	EXPECT_GT(freeCount, occupied.size());
	// The optical axis: free from the camera up to the wall, then the hit.
	for (int k = 0; k < 40; ++k)
	{
		const Voxel* v = g.find({0, 0, k});
		ASSERT_TRUE(v && v->isKnown()) << k;
		EXPECT_FLOAT_EQ(v->logOdds, o.logOddsMiss) << k;
	}
	EXPECT_FLOAT_EQ(g.find({0, 0, 40})->logOdds, o.logOddsHit);
	EXPECT_TRUE(!g.find({0, 0, 41}) || !g.find({0, 0, 41})->isKnown());
}

TEST(SubmappedIntegration, RepeatedFramesAccumulateAndClamp)
{
	DepthIntegrationOptions o;
	DepthFrameIntegrator integ(o);
	VoxelBlockGrid g(kRes);
	const auto cam = test::smallCamera();
	const auto upd = integ.castFrame(test::wallDepth(cam, 2.02f), cam, {}, kRes);
	for (int i = 0; i < 3; ++i) integ.apply(g, upd, i);
	EXPECT_FLOAT_EQ(g.find({0, 0, 40})->logOdds, 3 * o.logOddsHit);
	EXPECT_FLOAT_EQ(g.find({0, 0, 10})->logOdds, 3 * o.logOddsMiss);
	for (int i = 0; i < 10; ++i) integ.apply(g, upd, 3 + i);
	EXPECT_FLOAT_EQ(g.find({0, 0, 40})->logOdds, o.logOddsMax);
	EXPECT_FLOAT_EQ(g.find({0, 0, 10})->logOdds, o.logOddsMin);
	EXPECT_FLOAT_EQ(g.find({0, 0, 10})->travelled, 12.0f);
}

TEST(SubmappedIntegration, OccupiedWinsOverFreeInTheSameFrame)
{
	DepthIntegrationOptions o;
	DepthFrameIntegrator integ(o);
	// Ray 1 ends in voxel (0,0,10); ray 2 passes through it to (0,0,20).
	const std::vector<mrpt::math::TPoint3Df> pts = {{0.01f, 0.01f, 0.52f}, {0.01f, 0.01f, 1.02f}};
	const auto upd = integ.castPoints({0.01, 0.01, 0.01}, pts, kRes);
	EXPECT_EQ(upd.hitVoxels, 2u);
	EXPECT_EQ(upd.freeVoxels, 19u);  // voxels 0..19 crossed, minus the hit at 10
	VoxelBlockGrid g(kRes);
	integ.apply(g, upd, 0.0);
	EXPECT_FLOAT_EQ(g.find({0, 0, 10})->logOdds, o.logOddsHit);
	EXPECT_FLOAT_EQ(g.find({0, 0, 9})->logOdds, o.logOddsMiss);
	EXPECT_FLOAT_EQ(g.find({0, 0, 20})->logOdds, o.logOddsHit);
}

TEST(SubmappedIntegration, MaxRangeCutsRaysWithoutHits)
{
	DepthIntegrationOptions o;
	o.maxRange = 1.0;
	const VoxelBlockGrid g = integrateWall(o, 3.0f);
	EXPECT_EQ(g.numOccupiedVoxels(), 0u);
	EXPECT_GT(g.numKnownVoxels(), 0u);
	g.forEachKnown([&](const VoxelIndex& vi, const Voxel&) {
		const auto c = g.centreOf(vi);
		// strictly before the voxel of the cut point, which is at most 1 m away
		EXPECT_LT(std::sqrt(c.x * c.x + c.y * c.y + c.z * c.z), 1.0 + kRes);
	});
}

TEST_P(SubmappedIntegrationModes, DeterministicForAnyThreadCountAndSparsePath)
{
	const auto cam = test::smallCamera(80, 60, 70);
	const mrpt::poses::CPose3D T(0.3, -0.2, 0.1, 0.4, -0.2, 0.15);
	const cv::Mat depth = test::boxRoomDepth(cam, T, {-2, -1.5, -1}, {2.5, 1.5, 3});
	VoxelBlockGrid ref(kRes);
	for (unsigned threads : {1u, 2u, 3u})
	{
		DepthIntegrationOptions o;
		o.discretizeEndpoints = GetParam();
		o.threads = threads;
		DepthFrameIntegrator integ(o);
		VoxelBlockGrid g(kRes);
		const auto upd = integ.castFrame(depth, cam, T, kRes);
		EXPECT_FALSE(upd.sparsePath);
		integ.apply(g, upd, 0.5);
		if (threads == 1) ref = g;
		else EXPECT_TRUE(g == ref) << threads << " threads";
	}
	DepthIntegrationOptions o;
	o.discretizeEndpoints = GetParam();
	o.maxDenseMarkVoxels = 512;  // forces the sparse path
	DepthFrameIntegrator integ(o);
	VoxelBlockGrid g(kRes);
	const auto upd = integ.castFrame(depth, cam, T, kRes);
	EXPECT_TRUE(upd.sparsePath);
	integ.apply(g, upd, 0.5);
	EXPECT_TRUE(g == ref);
	EXPECT_EQ(upd.castRays, GetParam() ? upd.hitVoxels : upd.rays);  // all box rays hit
}

TEST(SubmappedIntegration, DecimationUsesEveryNthPixel)
{
	DepthIntegrationOptions o;
	o.pixelDecimation = 4;
	DepthFrameIntegrator integ(o);
	const auto cam = test::smallCamera();
	const auto upd = integ.castFrame(test::wallDepth(cam, 2.0f), cam, {}, kRes);
	EXPECT_EQ(upd.rays, (64u / 4) * (48u / 4));
}

TEST(SubmappedIntegration, OptionsValidateAndRoundTrip)
{
	DepthIntegrationOptions o;
	o.maxRange = -1;
	EXPECT_THROW(o.validate(), std::invalid_argument);
	try
	{
		o.validate();
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("maxRange"), std::string::npos) << e.what();
	}
	EXPECT_THROW(DepthFrameIntegrator{o}, std::invalid_argument);
	// Memory bounds: a dense mark volume beyond 2^30 one-byte voxels is refused.
	DepthIntegrationOptions big;
	big.maxDenseMarkVoxels = 1e30;
	EXPECT_THROW(big.validate(), std::invalid_argument);
	big.maxDenseMarkVoxels = 1073741824.0;
	EXPECT_NO_THROW(big.validate());

	// Every field, changed from its default, comes back through an INI section.
	DepthIntegrationOptions a;
	a.maxRange = 3.25;
	a.minRange = 0.35;
	a.pixelDecimation = 3;
	a.threads = 2;
	a.logOddsHit = 0.75f;
	a.logOddsMiss = -0.25f;
	a.logOddsMin = -1.5f;
	a.logOddsMax = 2.5f;
	a.discretizeEndpoints = false;
	a.maxDenseMarkVoxels = 4096.0;
	mrpt::config::CConfigFileMemory saved;
	a.saveToConfigFile(saved, "integration");
	const mrpt::config::CConfigFileMemory ini(saved.getContent());  // through the INI text
	DepthIntegrationOptions b;
	b.loadFromConfigFile(ini, "integration");
	EXPECT_DOUBLE_EQ(b.maxRange, a.maxRange);
	EXPECT_DOUBLE_EQ(b.minRange, a.minRange);
	EXPECT_EQ(b.pixelDecimation, a.pixelDecimation);
	EXPECT_EQ(b.threads, a.threads);
	EXPECT_FLOAT_EQ(b.logOddsHit, a.logOddsHit);
	EXPECT_FLOAT_EQ(b.logOddsMiss, a.logOddsMiss);
	EXPECT_FLOAT_EQ(b.logOddsMin, a.logOddsMin);
	EXPECT_FLOAT_EQ(b.logOddsMax, a.logOddsMax);
	EXPECT_EQ(b.discretizeEndpoints, a.discretizeEndpoints);
	EXPECT_DOUBLE_EQ(b.maxDenseMarkVoxels, a.maxDenseMarkVoxels);
	EXPECT_NO_THROW(b.validate());
}

TEST(SubmappedIntegration, ResolutionOutsideItsRangeIsRefusedNamingTheKey)
{
	// 1e-9 m voxels filled 8 GB in under a minute; 1e30 m is no map.
	for (const double r : {1e-9, 0.001, 0.0049, 10.5, 1e30, -0.05})
	{
		EXPECT_THROW(CSubmappedOccupancyGrid3D{r}, std::invalid_argument) << r;
		mrpt::config::CConfigFileMemory ini;
		ini.write("m_creationOpts", "resolution", std::to_string(r));
		CSubmappedOccupancyGrid3D::TMapDefinition def;
		try
		{
			def.loadFromConfigFile(ini, "m");
			ADD_FAILURE() << "resolution " << r << " accepted";
		}
		catch (const std::invalid_argument& e)
		{
			EXPECT_NE(std::string(e.what()).find("[m_creationOpts] resolution"), std::string::npos) << e.what();
		}
	}
	for (const double r : {CSubmappedOccupancyGrid3D::kMinResolution, 0.05, CSubmappedOccupancyGrid3D::kMaxResolution})
		EXPECT_NO_THROW(CSubmappedOccupancyGrid3D{r}) << r;
}
