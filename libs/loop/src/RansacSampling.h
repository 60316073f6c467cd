#pragma once
/** \file RansacSampling.h
 * The sampling steps shared by the 3-point RANSACs of libs/loop (RigidRansac.cpp,
 * Sim3Ransac.cpp). Internal to libs/loop.
 */
#include <cmath>
#include <cstddef>
#include <random>

namespace keygrid::loop::detail
{
/** Three distinct indices drawn by `pick` (uniform over [0, n), n >= 3) from `rng`. */
inline void drawThreeDistinct(std::mt19937_64& rng, std::uniform_int_distribution<std::size_t>& pick, std::size_t s[3])
{
	s[0] = pick(rng);
	do s[1] = pick(rng);
	while (s[1] == s[0]);
	do s[2] = pick(rng);
	while (s[2] == s[0] || s[2] == s[1]);
}

/** Hypotheses needed so that P(no all-inlier sample of 3) < 1 - confidence, once a hypothesis
 * has `inliers` of `n` pairs at iteration `it`; `current` when that gives no bound (no inliers). */
inline int ransacIterationsNeeded(int inliers, std::size_t n, double confidence, int it, int current)
{
	const double w = static_cast<double>(inliers) / static_cast<double>(n);
	const double pGood = w * w * w;
	if (pGood >= 1.0) return it + 1;
	if (pGood > 0) return static_cast<int>(std::ceil(std::log(1 - confidence) / std::log(1 - pGood)));
	return current;
}
}  // namespace keygrid::loop::detail
