#pragma once
/** \file RansacSampling.h
 * The sampling steps shared by the 3-point RANSACs of libs/loop (RigidRansac.cpp,
 * Sim3Ransac.cpp). Internal to libs/loop.
 */
#include <cmath>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
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

/** The hypothesis loop of a 3-point RANSAC over `n` >= 3 pairs: samples drawn with an RNG
 * seeded by `seed`, at most `maxIterations`, fewer once the best consensus shows that enough
 * were drawn (ransacIterationsNeeded at `confidence`). `hypothesis(s)` fits and scores the
 * sample s[3] and returns its inlier count when it became the best, nullopt otherwise (a
 * degenerate sample, or no better). Returns the number of samples drawn. */
template <class Hypothesis>
int runRansacHypotheses(std::uint64_t seed, std::size_t n, int maxIterations, double confidence, Hypothesis&& hypothesis)
{
	std::mt19937_64 rng(seed);
	std::uniform_int_distribution<std::size_t> pick(0, n - 1);
	int iterations = 0;
	int needed = maxIterations;
	for (int it = 0; it < std::min(needed, maxIterations); ++it)
	{
		++iterations;
		std::size_t s[3];
		drawThreeDistinct(rng, pick, s);
		if (const std::optional<int> best = hypothesis(s)) needed = ransacIterationsNeeded(*best, n, confidence, it, needed);
	}
	return iterations;
}
}  // namespace keygrid::loop::detail
