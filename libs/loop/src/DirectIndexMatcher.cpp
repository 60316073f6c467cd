#include "DescriptorMetric.h"

#include <keygrid/core/NearestTwo.h>
#include <keygrid/loop/DirectIndexMatcher.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace keygrid::loop
{
namespace
{
template <class Metric>
std::vector<DescriptorMatch> match(
	const Metric& m, bool squared, const cv::Mat& A, const FeatureVector& fvA, const cv::Mat& B, const FeatureVector& fvB,
	const DirectIndexMatchOptions& o)
{
	std::vector<DescriptorMatch> bestForB(static_cast<std::size_t>(B.rows));
	auto itA = fvA.begin();
	auto itB = fvB.begin();
	while (itA != fvA.end() && itB != fvB.end())
	{
		if (itA->first < itB->first) ++itA;
		else if (itB->first < itA->first) ++itB;
		else
		{
			for (int ia : itA->second)
			{
				core::NearestTwo<double> nearest;
				for (int ib : itB->second)
				{
					const double d = m.distance(A.ptr(ia), B.ptr(ib));
					nearest.add(squared ? std::sqrt(d) : d, ib);
				}
				const int bestB = nearest.index;
				const double best = nearest.best;
				if (bestB < 0 || best > o.maxDistance || !(best < o.ratio * nearest.second)) continue;
				auto& slot = bestForB[static_cast<std::size_t>(bestB)];
				if (slot.a < 0 || best < slot.distance) slot = DescriptorMatch{ia, bestB, best};
			}
			++itA;
			++itB;
		}
	}
	std::vector<DescriptorMatch> out;
	for (const auto& s : bestForB)
		if (s.a >= 0) out.push_back(s);
	std::sort(out.begin(), out.end(), [](const DescriptorMatch& x, const DescriptorMatch& y) { return x.a < y.a; });
	return out;
}
}  // namespace

std::vector<DescriptorMatch> matchByDirectIndex(
	const cv::Mat& descA, const FeatureVector& fvA, const cv::Mat& descB, const FeatureVector& fvB,
	const DirectIndexMatchOptions& opts)
{
	if (descA.empty() || descB.empty()) return {};
	if (descA.type() != descB.type() || descA.cols != descB.cols || (descA.type() != CV_8U && descA.type() != CV_32F))
		throw std::invalid_argument("matchByDirectIndex: descriptor sets of different or unsupported types");
	if (descA.type() == CV_8U) return match(detail::BinaryMetric{descA.cols}, false, descA, fvA, descB, fvB, opts);
	return match(detail::FloatMetric{descA.cols}, true, descA, fvA, descB, fvB, opts);
}

}  // namespace keygrid::loop
