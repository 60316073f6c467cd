/** 3D DDA traversal against a brute-force reference: every voxel of the segment's bounding box
 * whose box the segment crosses with positive length (slab test), in order of entry. */
#include <gtest/gtest.h>
#include <keygrid/maps/Dda.h>

#include <algorithm>
#include <random>
#include <set>

using keygrid::VoxelIndex;
using mrpt::math::TPoint3D;

namespace
{
/** Entry parameter t in [0,1] of segment a->b into voxel v, or -1 when it does not cross it
 * with positive length (Kay-Kajiya slab test). */
double entryParam(const TPoint3D& a, const TPoint3D& b, const VoxelIndex& v, double res)
{
	const double lo[3] = {v.x * res, v.y * res, v.z * res};
	const double p[3] = {a.x, a.y, a.z}, d[3] = {b.x - a.x, b.y - a.y, b.z - a.z};
	double t0 = 0, t1 = 1;
	for (int k = 0; k < 3; ++k)
	{
		if (d[k] == 0)
		{
			if (p[k] < lo[k] || p[k] >= lo[k] + res) return -1;
			continue;
		}
		double ta = (lo[k] - p[k]) / d[k], tb = (lo[k] + res - p[k]) / d[k];
		if (ta > tb) std::swap(ta, tb);
		t0 = std::max(t0, ta);
		t1 = std::min(t1, tb);
	}
	return t1 > t0 ? t0 : -1;
}

std::vector<VoxelIndex> bruteForce(const TPoint3D& a, const TPoint3D& b, double res)
{
	const auto va = VoxelIndex{int(std::floor(a.x / res)), int(std::floor(a.y / res)), int(std::floor(a.z / res))};
	const auto vb = VoxelIndex{int(std::floor(b.x / res)), int(std::floor(b.y / res)), int(std::floor(b.z / res))};
	std::vector<std::pair<double, VoxelIndex>> hits;
	for (int x = std::min(va.x, vb.x); x <= std::max(va.x, vb.x); ++x)
		for (int y = std::min(va.y, vb.y); y <= std::max(va.y, vb.y); ++y)
			for (int z = std::min(va.z, vb.z); z <= std::max(va.z, vb.z); ++z)
			{
				const double t = entryParam(a, b, {x, y, z}, res);
				if (t >= 0) hits.emplace_back(t, VoxelIndex{x, y, z});
			}
	std::sort(hits.begin(), hits.end(), [](const auto& p, const auto& q) { return p.first < q.first; });
	std::vector<VoxelIndex> out;
	for (const auto& h : hits) out.push_back(h.second);
	return out;
}
}  // namespace

TEST(Dda, MatchesBruteForceOnRandomSegments)
{
	std::mt19937 rng(42);
	std::uniform_real_distribution<double> U(-1.3, 1.3);
	for (double res : {0.05, 0.1, 0.37})
		for (int i = 0; i < 400; ++i)
		{
			const TPoint3D a(U(rng), U(rng), U(rng)), b(U(rng), U(rng), U(rng));
			const auto dda = keygrid::voxelsAlongSegment(a, b, res);
			const auto ref = bruteForce(a, b, res);
			ASSERT_EQ(dda.size(), ref.size()) << "segment " << a.asString() << " -> " << b.asString();
			for (std::size_t k = 0; k < ref.size(); ++k)
				ASSERT_EQ(dda[k], ref[k]) << "voxel " << k << " of " << a.asString() << " -> " << b.asString();
		}
}

TEST(Dda, ConsecutiveVoxelsAreFaceNeighboursAndEndsAreTheEndpointVoxels)
{
	std::mt19937 rng(7);
	std::uniform_real_distribution<double> U(-4, 4);
	for (int i = 0; i < 200; ++i)
	{
		const TPoint3D a(U(rng), U(rng), U(rng)), b(U(rng), U(rng), U(rng));
		const auto v = keygrid::voxelsAlongSegment(a, b, 0.05);
		ASSERT_FALSE(v.empty());
		EXPECT_EQ(v.front(), (VoxelIndex{int(std::floor(a.x / 0.05)), int(std::floor(a.y / 0.05)), int(std::floor(a.z / 0.05))}));
		EXPECT_EQ(v.back(), (VoxelIndex{int(std::floor(b.x / 0.05)), int(std::floor(b.y / 0.05)), int(std::floor(b.z / 0.05))}));
		// Manhattan length of the index walk = number of steps (closed form of the DDA).
		const auto& f = v.front();
		const auto& l = v.back();
		EXPECT_EQ(v.size() - 1, std::size_t(std::abs(l.x - f.x) + std::abs(l.y - f.y) + std::abs(l.z - f.z)));
		for (std::size_t k = 1; k < v.size(); ++k)
			ASSERT_EQ(std::abs(v[k].x - v[k - 1].x) + std::abs(v[k].y - v[k - 1].y) + std::abs(v[k].z - v[k - 1].z), 1);
	}
}

TEST(Dda, AxisAlignedAndDegenerateSegments)
{
	// Along +x from 0.01 to 0.49 with 0.1 m voxels: voxels 0..4.
	const auto v = keygrid::voxelsAlongSegment({0.01, 0.02, 0.03}, {0.49, 0.02, 0.03}, 0.1);
	ASSERT_EQ(v.size(), 5u);
	for (int i = 0; i < 5; ++i) EXPECT_EQ(v[i], (VoxelIndex{i, 0, 0}));
	// Negative direction across zero.
	const auto w = keygrid::voxelsAlongSegment({0.05, -0.05, 0.0}, {-0.25, -0.05, 0.0}, 0.1);
	ASSERT_EQ(w.size(), 4u);
	EXPECT_EQ(w.front(), (VoxelIndex{0, -1, 0}));
	EXPECT_EQ(w.back(), (VoxelIndex{-3, -1, 0}));
	// A point segment visits exactly its voxel.
	const auto p = keygrid::voxelsAlongSegment({-0.01, 0.0, 0.11}, {-0.01, 0.0, 0.11}, 0.1);
	ASSERT_EQ(p.size(), 1u);
	EXPECT_EQ(p[0], (VoxelIndex{-1, 0, 1}));
	// Early stop.
	std::size_t n = 0;
	keygrid::traverseSegment({0, 0, 0}, {1, 0, 0}, 0.1, [&](const VoxelIndex&) { return ++n < 3; });
	EXPECT_EQ(n, 3u);
}
