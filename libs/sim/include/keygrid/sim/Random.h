#pragma once
/** \file Random.h
 * Counter-based random numbers for the simulator: every value is a pure function of
 * (seed, stream, counters), so a frame renders to the same bytes whatever the thread schedule,
 * the platform's <random> implementation or the order in which frames are produced.
 */
#include <cmath>
#include <cstdint>

namespace keygrid::sim
{
/** SplitMix64 finaliser (Steele, Lea, Flood 2014): a bijective 64-bit mixer. */
inline std::uint64_t mix64(std::uint64_t z)
{
	z += 0x9E3779B97F4A7C15ULL;
	z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
	z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
	return z ^ (z >> 31);
}

/** Hash of up to four counters under a seed. */
inline std::uint64_t hashKey(
	std::uint64_t seed, std::uint64_t a, std::uint64_t b = 0, std::uint64_t c = 0)
{
	return mix64(mix64(mix64(mix64(seed) ^ a) ^ b) ^ c);
}

/** 64-bit FNV-1a of a string, used to derive per-object seeds from object names. */
inline std::uint64_t hashString(const char* s)
{
	std::uint64_t h = 0xCBF29CE484222325ULL;
	for (; *s; ++s) h = (h ^ static_cast<unsigned char>(*s)) * 0x100000001B3ULL;
	return h;
}

/** Uniform double in [0, 1) from the top 53 bits of a 64-bit word. */
inline double toUnit(std::uint64_t x) { return static_cast<double>(x >> 11) * 0x1.0p-53; }

/** Sequential generator (SplitMix64) with portable uniform and Gaussian draws. */
class Rng
{
   public:
	explicit Rng(std::uint64_t seed) : m_state(seed) {}

	std::uint64_t next()
	{
		m_state += 0x9E3779B97F4A7C15ULL;
		std::uint64_t z = m_state;
		z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
		z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
		return z ^ (z >> 31);
	}
	/** Uniform in [0, 1). */
	double uniform() { return toUnit(next()); }
	/** Uniform in [lo, hi). */
	double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
	/** Uniform integer in [0, n), n > 0 (modulo bias < 2^-40 for n < 2^24). */
	int below(int n) { return static_cast<int>(next() % static_cast<std::uint64_t>(n)); }
	/** Standard normal (Box-Muller, one of the pair). */
	double gaussian()
	{
		const double u1 = 1.0 - uniform();  // (0, 1]
		const double u2 = uniform();
		return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
	}

   private:
	std::uint64_t m_state;
};

}  // namespace keygrid::sim
