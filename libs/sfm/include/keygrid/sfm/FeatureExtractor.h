#pragma once
/** \file FeatureExtractor.h
 * Keypoints and descriptors of a frame: ORB (default) or SIFT, spread evenly over the image by
 * grid bucketing, undistorted, with a validated depth per keypoint.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/Frame.h>
#include <keygrid/core/OptionFields.h>
#include <keygrid/sfm/FrameFeatures.h>
#include <opencv2/features2d.hpp>

#include <string>

namespace keygrid::sfm
{
struct FeatureOptions : public core::FieldTableOptions<FeatureOptions>
{
	/** "orb" or "sift" (Default: orb) */
	std::string type{"orb"};
	/** Upper bound of num_features (memory and time per frame). */
	static constexpr int kMaxFeatures = 100000;
	/** Keypoints kept per frame after bucketing, in [10, kMaxFeatures] (Default: 1000) */
	int numFeatures{1000};
	/** Pyramid scale step (Default: 1.2) */
	double scaleFactor{1.2};
	/** Pyramid levels (Default: 8) */
	int numLevels{8};
	/** FAST threshold for ORB (Default: 20) */
	int fastThreshold{20};
	/** Candidates detected per kept keypoint before bucketing (Default: 2.0) */
	double oversampling{2.0};
	/** Bucketing grid: columns x rows of cells sharing the keypoint budget (Default: 8 x 6) */
	int gridCols{8}, gridRows{6};
	/** Valid depth range [m] (Default: 0.3 .. 6.0 m) */
	double minDepth{0.3}, maxDepth{6.0};
	/** A depth is rejected when the 3x3 neighbourhood spans more than this fraction of it,
	 * i.e. the keypoint sits on a depth discontinuity (Default: 0.05) */
	double maxDepthDiscontinuity{0.05};
	/** ORB only: map keypoints found on pyramid level l to level 0 through the pyramid's pixel
	 * centres, u0 = (u_l + 0.5) * W0 / W_l - 0.5 (W_l = the level's rounded width), instead of
	 * OpenCV's u_l * scale^l, which is off by up to 1.3 px at level 7 (Default: true) */
	bool pyramidPixelCentres{true};

	/** The [features] keys. */
	core::OptionFields fields();
	/** Throws std::invalid_argument naming section, key, value and rule of an invalid option. */
	void validate(const std::string& section = "features") const;
};

class FeatureExtractor
{
   public:
	explicit FeatureExtractor(const FeatureOptions& opts);

	/** Detects, buckets, describes, undistorts and looks up depth. Thread-compatible: one
	 * extractor per thread. */
	FrameFeatures extract(const core::Frame& frame) const;

	const FeatureOptions& options() const { return m_opts; }
	/** Scale of pyramid level l (scaleFactor^l). */
	double levelScale(int level) const;

	/** Depth at a raw (distorted) pixel with the validity checks of the options, 0 if invalid. */
	float depthAt(const cv::Mat& depth, float u, float v) const;

	/** Level-0 position of an ORB keypoint that OpenCV reports as pt = p_l * scale^l (see
	 * FeatureOptions::pyramidPixelCentres); level 0 and non-ORB keypoints are returned as is. */
	cv::Point2f levelZeroPosition(const cv::KeyPoint& kp, cv::Size imageSize) const;

   private:
	FeatureOptions m_opts;
	cv::Ptr<cv::Feature2D> m_detector;
	std::vector<double> m_levelScale;
};

/** Keeps at most `budget` keypoints spread over a cols x rows grid: each cell first keeps its
 * strongest `budget / cells`, then the remaining budget goes to the strongest leftovers. */
std::vector<cv::KeyPoint> bucketKeypoints(
	const std::vector<cv::KeyPoint>& kps, cv::Size imageSize, int cols, int rows, int budget);

}  // namespace keygrid::sfm
