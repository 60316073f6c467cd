/** Bresenham and Wu (anti-aliased) ray traversal against brute-force references. */
#include <keygrid/maps/GridRayTraversal.h>

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

using namespace keygrid::maps;

namespace
{
/** Brute force: the exact line's minor coordinate at each integer major coordinate. */
double exactMinor(int i, int x0, int y0, int x1, int y1, bool steep)
{
	if (steep) std::swap(x0, y0), std::swap(x1, y1);
	if (x1 == x0) return y0;
	return y0 + static_cast<double>(y1 - y0) * (i - x0) / (x1 - x0);
}
}  // namespace

TEST(ISMRayTraversal, BresenhamMatchesNearestCellBruteForce)
{
	std::mt19937 rng(7);
	std::uniform_int_distribution<int> U(-40, 40);
	for (int trial = 0; trial < 2000; trial++)
	{
		const int x0 = U(rng), y0 = U(rng), x1 = U(rng), y1 = U(rng);
		const auto cells = bresenhamCells(x0, y0, x1, y1);
		const bool steep = std::abs(y1 - y0) > std::abs(x1 - x0);
		const int n = std::max(std::abs(x1 - x0), std::abs(y1 - y0));
		ASSERT_EQ(cells.size(), static_cast<size_t>(n + 1));
		EXPECT_EQ(cells.front().cx, x0);
		EXPECT_EQ(cells.front().cy, y0);
		EXPECT_EQ(cells.back().cx, x1);
		EXPECT_EQ(cells.back().cy, y1);
		for (size_t k = 0; k < cells.size(); k++)
		{
			const int major = steep ? cells[k].cy : cells[k].cx;
			const int minor = steep ? cells[k].cx : cells[k].cy;
			// One cell per major step, in order.
			const int sgn = steep ? (y1 >= y0 ? 1 : -1) : (x1 >= x0 ? 1 : -1);
			ASSERT_EQ(major, (steep ? y0 : x0) + sgn * static_cast<int>(k));
			// The brute-force nearest cell to the exact line (ties: either one).
			const double exact = exactMinor(major, x0, y0, x1, y1, steep);
			ASSERT_LE(std::abs(minor - exact), 0.5 + 1e-9)
				<< "(" << x0 << "," << y0 << ")->(" << x1 << "," << y1 << ") step " << k;
		}
	}
}

TEST(ISMRayTraversal, WuWeightsSumToOneAndCentroidIsOnTheLine)
{
	std::mt19937 rng(11);
	std::uniform_real_distribution<double> U(-30.0, 30.0);
	for (int trial = 0; trial < 1000; trial++)
	{
		const double x0 = U(rng), y0 = U(rng), x1 = U(rng), y1 = U(rng);
		const bool steep = std::abs(y1 - y0) > std::abs(x1 - x0);
		std::map<int, std::pair<double, double>> perStep;  // major -> (sum w, sum w*minor)
		for (const auto& c : wuCells(x0, y0, x1, y1))
		{
			ASSERT_GT(c.weight, 0.0f);
			ASSERT_LE(c.weight, 1.0f);
			const int major = steep ? c.cy : c.cx;
			const int minor = steep ? c.cx : c.cy;
			perStep[major].first += c.weight;
			perStep[major].second += c.weight * minor;
		}
		const double a0 = steep ? y0 : x0, a1 = steep ? y1 : x1;
		const double b0 = steep ? x0 : y0, b1 = steep ? x1 : y1;
		ASSERT_EQ(perStep.size(), static_cast<size_t>(std::abs(std::lround(a1) - std::lround(a0)) + 1));
		for (const auto& [major, sw] : perStep)
		{
			EXPECT_NEAR(sw.first, 1.0, 1e-6);
			// Weighted minor coordinate = the exact line at this major coordinate.
			const double exact = a1 == a0 ? b0 : b0 + (b1 - b0) * (major - a0) / (a1 - a0);
			EXPECT_NEAR(sw.second / sw.first, exact, 1e-5);
		}
	}
}

TEST(ISMRayTraversal, AxisAlignedAndDiagonalCases)
{
	const auto h = bresenhamCells(0, 0, 5, 0);
	ASSERT_EQ(h.size(), 6u);
	for (int i = 0; i <= 5; i++) EXPECT_EQ(h[static_cast<size_t>(i)].cx, i);
	const auto d = bresenhamCells(0, 0, -4, -4);
	ASSERT_EQ(d.size(), 5u);
	for (int i = 0; i <= 4; i++) EXPECT_EQ(d[static_cast<size_t>(i)].cy, -i);
	// A Wu line exactly through cell centres puts all weight on one cell per step.
	const auto w = wuCells(0.0, 2.0, 6.0, 2.0);
	ASSERT_EQ(w.size(), 7u);
	for (const auto& c : w)
	{
		EXPECT_EQ(c.cy, 2);
		EXPECT_FLOAT_EQ(c.weight, 1.0f);
	}
	EXPECT_EQ(bresenhamCells(3, 3, 3, 3).size(), 1u);
}
