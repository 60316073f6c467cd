// The bit counts used for binary descriptors (inline, and the table scan with its POPCNT build)
// against std::bitset (an independent count).
#include <gtest/gtest.h>
#include <keygrid/core/Hamming.h>

#include <bitset>
#include <random>

using keygrid::core::hammingDistance;
using keygrid::core::popcount64;

TEST(Hamming, PopcountMatchesBitsetOnEdgeAndRandomWords)
{
	for (std::uint64_t x : {0ULL, 1ULL, ~0ULL, 0x8000000000000000ULL, 0x5555555555555555ULL, 0xF0F0F0F0F0F0F0F0ULL})
		EXPECT_EQ(popcount64(x), static_cast<int>(std::bitset<64>(x).count())) << x;
	std::mt19937_64 g(7);
	for (int i = 0; i < 100000; i++)
	{
		const std::uint64_t x = g();
		ASSERT_EQ(popcount64(x), static_cast<int>(std::bitset<64>(x).count())) << x;
	}
}

TEST(Hamming, DistanceOfOrbSizedDescriptors)
{
	std::mt19937_64 g(11);
	std::uint64_t a[4], b[4];
	for (int i = 0; i < 4; i++) a[i] = b[i] = g();
	EXPECT_EQ(hammingDistance(a, b, 4), 0);
	b[0] ^= 1ULL;
	b[3] ^= 0xFFULL << 40;
	EXPECT_EQ(hammingDistance(a, b, 4), 9);
	for (int i = 0; i < 4; i++) b[i] = ~a[i];
	EXPECT_EQ(hammingDistance(a, b, 4), 256);
}

TEST(Hamming, DistancesAgainstATableMatchBitsetCounts)
{
	// A table of 37 descriptors of 4 words in rows of 5 words (a padded stride), against one
	// query; the last row differs in every bit, the first in none.
	std::mt19937_64 g(23);
	constexpr int kRows = 37, kWords = 4;
	constexpr std::size_t kStride = 5;
	std::uint64_t q[kWords], table[kRows * kStride];
	for (auto& w : q) w = g();
	for (auto& w : table) w = g();
	for (int w = 0; w < kWords; w++) table[w] = q[w], table[(kRows - 1) * kStride + w] = ~q[w];
	int out[kRows];
	keygrid::core::hammingDistances(q, table, kStride, kRows, kWords, out);
	for (int r = 0; r < kRows; r++)
	{
		std::size_t bits = 0;
		for (int w = 0; w < kWords; w++) bits += std::bitset<64>(q[w] ^ table[r * kStride + w]).count();
		EXPECT_EQ(out[r], static_cast<int>(bits)) << "row " << r;
	}
	EXPECT_EQ(out[0], 0);
	EXPECT_EQ(out[kRows - 1], 256);
}
