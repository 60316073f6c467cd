#pragma once
/** \file FrameFeatures.h
 * The features of one frame and a grid to find them by image area.
 */
#include <keygrid/core/RgbdCamera.h>
#include <opencv2/core.hpp>

#include <vector>

namespace keygrid::sfm
{
/** Keypoints of a frame. Index i refers to the same keypoint in every vector. */
struct FrameFeatures
{
	/** Keypoints as detected, in the raw (distorted) image; octave = pyramid level. */
	std::vector<cv::KeyPoint> keypoints;
	/** Undistorted pixel positions (pinhole model with the camera's K). */
	std::vector<cv::Point2f> undistorted;
	/** One descriptor per row (CV_8U 32 bytes for ORB, CV_32F 128 for SIFT). */
	cv::Mat descriptors;
	/** Depth [m] at each keypoint, 0 where invalid. */
	std::vector<float> depth;
	/** Intrinsics of the image (distortion already removed from `undistorted`). */
	core::RgbdCamera camera;
	/** Pyramid scale per level (scale^level), copied from the extractor. */
	std::vector<double> levelScale;
	/** Number of pyramid levels the extractor used. */
	int numLevels{8};

	std::size_t size() const { return keypoints.size(); }
	bool isBinary() const { return descriptors.type() == CV_8U; }

	/** Builds the lookup grid; call after filling (or changing) `undistorted`. */
	void buildGrid(int cellSizePx = 16);
	/** Cell size of the lookup grid [px]. */
	int gridCellSize() const { return m_cell; }
	/** Indices of keypoints whose undistorted position lies within radius r of (u, v) and whose
	 * level is in [minLevel, maxLevel] (-1: unbounded). */
	std::vector<int> featuresInArea(float u, float v, float r, int minLevel = -1, int maxLevel = -1) const;
	/** The same into `out` (cleared first), reusing its memory across calls. */
	void featuresInArea(float u, float v, float r, int minLevel, int maxLevel, std::vector<int>& out) const;
	/** Whether featuresInArea would return anything (stops at the first keypoint found). */
	bool anyFeatureInArea(float u, float v, float r, int minLevel = -1, int maxLevel = -1) const;

   private:
	/** Calls visit(i) for each keypoint of the area in grid order until it returns false. */
	template <class Visit>
	void visitArea(float u, float v, float r, int minLevel, int maxLevel, Visit&& visit) const;

	int m_cell{16}, m_cols{0}, m_rows{0};
	/** The grid, compact (keyframes keep it for their lifetime): the keypoints of cell c are
	 * m_cellItems[m_cellStart[c] .. m_cellStart[c + 1]), in index order; cells row-major. */
	std::vector<int> m_cellStart, m_cellItems;
};

/** Distance between two descriptors: Hamming for binary, L2 for float. */
float descriptorDistance(const cv::Mat& a, const cv::Mat& b);
/** The same between row `ra` of `a` and row `rb` of `b`, without building a cv::Mat header per
 * row (matching loops call this for every candidate pair). */
float descriptorDistance(const cv::Mat& a, int ra, const cv::Mat& b, int rb);

}  // namespace keygrid::sfm
