#include <keygrid/core/NearestTwo.h>
#include <keygrid/sfm/InitialMatcher.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace keygrid::sfm
{
namespace
{
constexpr int kOrientationBins = 30;

/** Indices of the three fullest bins (-1 for a bin that holds less than a tenth of the
 * fullest, as ORB-SLAM's ComputeThreeMaxima: a mode that small is made of wrong matches). */
std::array<int, 3> threeFullest(const std::array<std::vector<int>, kOrientationBins>& bins)
{
	std::array<int, 3> best{-1, -1, -1};
	std::array<std::size_t, 3> size{0, 0, 0};
	for (int b = 0; b < kOrientationBins; b++)
	{
		const std::size_t s = bins[b].size();
		if (s > size[0])
		{
			size = {s, size[0], size[1]};
			best = {b, best[0], best[1]};
		}
		else if (s > size[1])
		{
			size = {size[0], s, size[1]};
			best = {best[0], b, best[1]};
		}
		else if (s > size[2])
		{
			size[2] = s;
			best[2] = b;
		}
	}
	for (int k = 1; k < 3; k++)
		if (static_cast<double>(size[k]) < 0.1 * static_cast<double>(size[0])) best[k] = -1;
	return best;
}
}  // namespace

int searchForInitialization(
	const FrameFeatures& ref, const FrameFeatures& cur, std::vector<cv::Point2f>& predicted, const InitialMatchOptions& o,
	std::vector<int>& refToCur)
{
	if (predicted.size() != ref.size())
		throw std::invalid_argument(
			"searchForInitialization: " + std::to_string(predicted.size()) + " predicted positions for " + std::to_string(ref.size()) +
			" reference keypoints");
	refToCur.assign(ref.size(), -1);
	// Each current keypoint keeps the reference keypoint closest in descriptor space.
	std::vector<int> curToRef(cur.size(), -1);
	std::vector<float> curBest(cur.size(), std::numeric_limits<float>::max());
	std::vector<int> area;
	int n = 0;
	for (std::size_t i = 0; i < ref.size(); i++)
	{
		const int level = ref.keypoints[i].octave;
		// The window bounds the image motion, which does not depend on the level.
		cur.featuresInArea(predicted[i].x, predicted[i].y, o.windowPx, std::max(0, level - 1), level + 1, area);
		core::NearestTwo<float> nearest;
		for (int j : area) nearest.add(descriptorDistance(ref.descriptors, static_cast<int>(i), cur.descriptors, j), j);
		const int bestIdx = nearest.index;
		const float best = nearest.best;
		if (bestIdx < 0 || best > o.maxDistance || !(best < o.ratio * nearest.second)) continue;
		if (curToRef[bestIdx] >= 0)
		{
			if (curBest[bestIdx] <= best) continue;  // that keypoint has a closer reference keypoint
			refToCur[curToRef[bestIdx]] = -1;
			--n;
		}
		refToCur[i] = bestIdx;
		curToRef[bestIdx] = static_cast<int>(i);
		curBest[bestIdx] = best;
		++n;
	}
	if (o.checkOrientation && n > 0)
	{
		std::array<std::vector<int>, kOrientationBins> bins;
		for (std::size_t i = 0; i < ref.size(); i++)
		{
			if (refToCur[i] < 0) continue;
			float rot = ref.keypoints[i].angle - cur.keypoints[refToCur[i]].angle;
			if (rot < 0) rot += 360.f;
			const int b = std::min(kOrientationBins - 1, static_cast<int>(rot * kOrientationBins / 360.f));
			bins[b].push_back(static_cast<int>(i));
		}
		const auto keep = threeFullest(bins);
		for (int b = 0; b < kOrientationBins; b++)
		{
			if (b == keep[0] || b == keep[1] || b == keep[2]) continue;
			for (int i : bins[b])
			{
				refToCur[i] = -1;
				--n;
			}
		}
	}
	for (std::size_t i = 0; i < ref.size(); i++)
		if (refToCur[i] >= 0) predicted[i] = cur.undistorted[refToCur[i]];
	return n;
}

}  // namespace keygrid::sfm
