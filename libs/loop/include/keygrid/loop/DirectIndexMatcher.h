#pragma once
/** \file DirectIndexMatcher.h
 * Descriptor matching between two keyframes accelerated by the vocabulary's direct index
 * (FeatureVector): only features under the same tree node are compared, as DBoW2/ORB-SLAM's
 * SearchByBoW. Generic: descriptors are cv::Mat rows (CV_8U Hamming or CV_32F L2).
 */
#include <keygrid/loop/BowVector.h>
#include <opencv2/core.hpp>

#include <vector>

namespace keygrid::loop
{
struct DirectIndexMatchOptions
{
	/** Largest accepted distance: Hamming bits for binary, Euclidean for float (Default: 50, ORB-SLAM's TH_LOW) */
	double maxDistance{50.0};
	/** Best must be below ratio x second best under the same node (Default: 0.75) */
	double ratio{0.75};
};

struct DescriptorMatch
{
	int a{-1}, b{-1};  //!< row in descriptors A and B
	double distance{0};
};

/** Matches rows of descA to rows of descB; each row of B is used at most once (the closest A
 * wins). fvA / fvB come from Vocabulary::transform(desc, fv, level) with the same level.
 * Throws std::invalid_argument when the descriptor types or widths differ. */
std::vector<DescriptorMatch> matchByDirectIndex(
	const cv::Mat& descA, const FeatureVector& fvA, const cv::Mat& descB, const FeatureVector& fvB,
	const DirectIndexMatchOptions& opts = {});

}  // namespace keygrid::loop
