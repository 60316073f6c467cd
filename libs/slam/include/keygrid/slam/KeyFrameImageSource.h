#pragma once
/** \file KeyFrameImageSource.h
 * Where the images of a keyframe come from once they may have left the keyframe
 * (sfm::KeyFrame::depth / colour): the run's KeyFrameImageCache, a stored session, or the
 * keyframe itself (KeyFrameImagesInRam). Readers that need a keyframe's images after its
 * insertion into the metric maps (keyframes.simplemap, dense 2D input waiting for the floor)
 * go through one.
 */
#include <keygrid/sfm/SparseMap.h>
#include <opencv2/core.hpp>

namespace keygrid::slam
{
/** The images of one keyframe, as sfm::KeyFrame holds them. */
struct KeyFrameImageData
{
	/** Depth [m], CV_32FC1; empty when the keyframe has none */
	cv::Mat depth;
	/** Colour (BGR, CV_8UC3) or grey (CV_8UC1) image; empty when the keyframe has none */
	cv::Mat colour;
};

class KeyFrameImageSource
{
   public:
	virtual ~KeyFrameImageSource() = default;
	/** Whether keyframe `kf` has both a depth and an image, without decoding them. */
	virtual bool hasImages(const sfm::KeyFrame& kf) const = 0;
	/** The images of keyframe `kf` (empty mats for what it has none of). */
	virtual KeyFrameImageData load(const sfm::KeyFrame& kf) const = 0;
};

/** The images each keyframe still holds itself. */
class KeyFrameImagesInRam : public KeyFrameImageSource
{
   public:
	bool hasImages(const sfm::KeyFrame& kf) const override { return !kf.depth.empty() && !kf.colour.empty(); }
	KeyFrameImageData load(const sfm::KeyFrame& kf) const override { return {kf.depth, kf.colour}; }
};

}  // namespace keygrid::slam
