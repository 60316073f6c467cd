// Ground-truth occupancy equals the analytic surface voxels / cells of the scene geometry.
#include <keygrid/sim/GroundTruthOccupancy.h>

#include "SimTestScenes.h"
#include "TestData.h"

#include <cmath>
#include <cstdio>
#include <fstream>

using namespace keygrid;

namespace
{
// One static box [lo, hi] (corners off the voxel grid) plus a dynamic one that must be ignored.
const Eigen::Vector3d lo(0.313, -0.472, 0.0), hi(1.127, 0.261, 1.93);

std::string boxSceneIni(const Eigen::Vector3d& lo = ::lo, const Eigen::Vector3d& hi = ::hi)
{
	const Eigen::Vector3d c = 0.5 * (lo + hi), s = hi - lo;
	char buf[512];
	std::snprintf(
		buf, sizeof(buf),
		"[object.box]\ntype = box\ncentre = %.6f %.6f %.6f\nsize = %.6f %.6f %.6f\n"
		"[object.mover]\ntype = box\ncentre = 3 3 1\nsize = 1 1 1\ndynamic = true\n",
		c.x(), c.y(), c.z(), s.x(), s.y(), s.z());
	return "[scene]\nframes = 1\n" + test::tinyCameraIni() +
		   "[trajectory]\nwp_00 = -3 0 1  0 0 1\n" + buf;
}

// The half-open cell [a, a + r) along one axis against the closed interval [l, h]:
// meets it when a <= h and a + r > l; lies inside the open interior when a > l and a + r <= h.
bool meets(double a, double r, double l, double h) { return a <= h && a + r > l; }
bool interior(double a, double r, double l, double h) { return a > l && a + r <= h; }
// The closed cell [a, a + r] (floor plans: a face on a cell boundary marks both cells); eps
// absorbs the rounding of a + r for lattice coordinates.
constexpr double eps = 1e-9;
bool meetsClosed(double a, double r, double l, double h) { return a <= h + eps && a + r >= l - eps; }
bool interiorClosed(double a, double r, double l, double h)
{
	return a > l + eps && a + r < h - eps;
}
}  // namespace

class VoxelResolution : public ::testing::TestWithParam<double>
{
};

TEST_P(VoxelResolution, BoxSurfaceVoxelsAreExact)
{
	const double r = GetParam();
	const sim::Scene scene = test::sceneFromString(boxSceneIni());
	const sim::VoxelSet vs = sim::voxeliseStaticScene(scene, r);
	// A voxel holds part of the box surface iff it meets the closed box and is not inside
	// its open interior (voxels are convex, so they then contain a boundary point).
	std::size_t expected = 0;
	const int i0 = static_cast<int>(std::floor(lo.x() / r)) - 2,
			  i1 = static_cast<int>(std::floor(hi.x() / r)) + 2;
	const int j0 = static_cast<int>(std::floor(lo.y() / r)) - 2,
			  j1 = static_cast<int>(std::floor(hi.y() / r)) + 2;
	const int k0 = static_cast<int>(std::floor(lo.z() / r)) - 2,
			  k1 = static_cast<int>(std::floor(hi.z() / r)) + 2;
	for (int i = i0; i <= i1; i++)
		for (int j = j0; j <= j1; j++)
			for (int k = k0; k <= k1; k++)
			{
				const double a[3] = {i * r, j * r, k * r};
				bool meet = true, inside = true;
				for (int ax = 0; ax < 3; ax++)
				{
					meet = meet && meets(a[ax], r, lo[ax], hi[ax]);
					inside = inside && interior(a[ax], r, lo[ax], hi[ax]);
				}
				const bool surface = meet && !inside;
				expected += surface;
				ASSERT_EQ(vs.contains({i, j, k}), surface) << "voxel " << i << " " << j << " " << k;
			}
	EXPECT_EQ(vs.size(), expected);  // nothing else (the dynamic box is left out)
	EXPECT_FALSE(vs.containsPoint(Eigen::Vector3d(3, 3, 1.5)));
}

INSTANTIATE_TEST_SUITE_P(Sim, VoxelResolution, ::testing::Values(0.05, 0.1, 0.137));

TEST(GroundTruthOccupancy, FloorPlanIsTheBoxOutlineInTheBand)
{
	const double r = 0.05;
	const sim::Scene scene = test::sceneFromString(boxSceneIni());
	// The band 0.1 .. 1.8 m cuts the box's vertical faces only (top at 1.93 m, bottom at 0).
	const sim::FloorPlan fp = sim::floorPlanOfStaticScene(scene, r, 0.1, 1.8);
	std::size_t expected = 0;
	for (int cy = 0; cy < fp.height; cy++)
		for (int cx = 0; cx < fp.width; cx++)
		{
			const double ax = fp.origin.x() + cx * r, ay = fp.origin.y() + cy * r;
			const bool outline =
				meets(ax, r, lo.x(), hi.x()) && meets(ay, r, lo.y(), hi.y()) &&
				!(interior(ax, r, lo.x(), hi.x()) && interior(ay, r, lo.y(), hi.y()));
			expected += outline;
			ASSERT_EQ(fp.occupiedAt(cx, cy), outline) << "cell " << cx << " " << cy;
		}
	EXPECT_EQ(fp.occupiedCount(), expected);
	EXPECT_GT(expected, 0u);
}

TEST(GroundTruthOccupancy, FloorPlanFacesOnCellBoundariesMarkBothCells)
{
	// Corners on the 5 cm lattice, like the walls of config/sim/room_loop.ini: each vertical
	// face lies on a cell boundary, so the closed cells on both sides hold part of it.
	const double r = 0.05;
	const Eigen::Vector3d bl(0.5, -0.25, 0.0), bh(1.25, 0.4, 1.95);  // top above the band
	const sim::Scene scene = test::sceneFromString(boxSceneIni(bl, bh));
	const sim::FloorPlan fp = sim::floorPlanOfStaticScene(scene, r, 0.1, 1.8);
	std::size_t expected = 0;
	for (int cy = 0; cy < fp.height; cy++)
		for (int cx = 0; cx < fp.width; cx++)
		{
			const double ax = fp.origin.x() + cx * r, ay = fp.origin.y() + cy * r;
			const bool outline = meetsClosed(ax, r, bl.x(), bh.x()) &&
								 meetsClosed(ay, r, bl.y(), bh.y()) &&
								 !(interiorClosed(ax, r, bl.x(), bh.x()) &&
								   interiorClosed(ay, r, bl.y(), bh.y()));
			expected += outline;
			ASSERT_EQ(fp.occupiedAt(cx, cy), outline) << "cell " << cx << " " << cy;
		}
	EXPECT_EQ(fp.occupiedCount(), expected);
	// A 15 x 13 cell box: outline rings just inside and just outside the faces.
	EXPECT_EQ(expected, std::size_t(2 * (15 + 13) - 4 + 2 * (17 + 15) - 4));
}

TEST(GroundTruthOccupancy, FilesRoundTrip)
{
	const sim::Scene scene = test::sceneFromString(boxSceneIni());
	const std::string dir = test::scratchDir("sim_occupancy_io");
	const sim::VoxelSet vs =
		sim::voxeliseStaticScene(scene, 0.1, Eigen::Vector3d(0.01, 0.02, 0.03));
	vs.save(dir + "/v.txt");
	const sim::VoxelSet back = sim::VoxelSet::load(dir + "/v.txt");
	EXPECT_EQ(back.voxels(), vs.voxels());
	EXPECT_DOUBLE_EQ(back.resolution(), 0.1);
	EXPECT_DOUBLE_EQ(back.origin().y(), 0.02);

	const sim::FloorPlan fp = sim::floorPlanOfStaticScene(scene, 0.05, 0.1, 1.8);
	fp.save(dir + "/plan");
	const sim::FloorPlan fb = sim::FloorPlan::load(dir + "/plan.yaml");
	EXPECT_EQ(fb.width, fp.width);
	EXPECT_EQ(fb.height, fp.height);
	EXPECT_EQ(fb.occupied, fp.occupied);
	EXPECT_NEAR(fb.origin.x(), fp.origin.x(), 1e-9);
	EXPECT_NEAR(fb.origin.y(), fp.origin.y(), 1e-9);

	// A damaged voxel file names the line.
	{
		std::ofstream f(dir + "/bad.txt");
		f << "KEYGRID_VOXELS 2\nresolution 0.1\norigin 0 0 0\ncount 0\n";
	}
	try
	{
		sim::VoxelSet::load(dir + "/bad.txt");
		FAIL() << "version 2 accepted";
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_NE(std::string(e.what()).find("bad.txt:1"), std::string::npos) << e.what();
	}
}
