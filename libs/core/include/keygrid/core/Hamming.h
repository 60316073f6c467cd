#pragma once
/** Hamming distance of binary descriptors (ORB: 32 bytes = 4 words), the inner loop of all
 * descriptor matching and of the vocabulary tree.
 *
 * Debian builds for baseline x86-64, which has no POPCNT instruction: there
 * __builtin_popcountll becomes a call into libgcc, a visible share of a keygrid-slam run's
 * time. Without -mpopcnt the bit count is done inline instead, by the classic parallel
 * ("SWAR") reduction: sums of 2, 4, 8 bits in place, then one multiply adds the 8 byte sums
 * into the top byte. */
#include <cstddef>
#include <cstdint>

namespace keygrid::core
{
inline int popcount64(std::uint64_t x)
{
#if defined(__POPCNT__)
	return __builtin_popcountll(x);
#else
	x = x - ((x >> 1) & 0x5555555555555555ULL);
	x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
	x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0FULL;
	return static_cast<int>((x * 0x0101010101010101ULL) >> 56);
#endif
}

/** Bits that differ between two descriptors of `words` 64-bit words. */
inline int hammingDistance(const std::uint64_t* a, const std::uint64_t* b, int words)
{
	int d = 0;
	for (int w = 0; w < words; w++) d += popcount64(a[w] ^ b[w]);
	return d;
}

/** out[r] = hammingDistance(q, rows + r * strideWords, words) for r in [0, n): one descriptor
 * against a table of them, the inner loop of brute-force matching. On x86-64 without -mpopcnt
 * it runs a POPCNT build of the loop when the CPU has the instruction (checked once), the
 * inline count otherwise; both give the same distances. */
void hammingDistances(const std::uint64_t* q, const std::uint64_t* rows, std::size_t strideWords, int n, int words, int* out);
}  // namespace keygrid::core
