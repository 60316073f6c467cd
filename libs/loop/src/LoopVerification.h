#pragma once
/** \file LoopVerification.h
 * The geometric check of a loop candidate shared by LoopCloser's rigid (RGB-D) and similarity
 * (monocular) paths. Internal to libs/loop.
 */
#include <keygrid/loop/LoopCloser.h>

#include <optional>

namespace keygrid::loop::detail
{
/** The RANSAC of a loop query over its rec.matches correspondences, with the outcome recorded:
 * FewMatches when there are fewer than `minInliers` (the RANSAC is not run), RansacFailed when
 * `ransac()` finds no model; rec.inliers from the RANSAC. The result when it succeeded. */
template <class Ransac>
auto verifiedByRansac(LoopQueryRecord& rec, int minInliers, Ransac&& ransac) -> std::optional<decltype(ransac())>
{
	if (rec.matches < minInliers)
	{
		rec.outcome = LoopQueryOutcome::FewMatches;
		return std::nullopt;
	}
	auto r = ransac();
	rec.inliers = r.numInliers;
	if (!r.success)
	{
		rec.outcome = LoopQueryOutcome::RansacFailed;
		return std::nullopt;
	}
	return r;
}
}  // namespace keygrid::loop::detail
