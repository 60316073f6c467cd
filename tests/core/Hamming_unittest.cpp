// The inline bit count used for binary descriptors against std::bitset (an independent count).
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
