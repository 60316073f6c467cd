#pragma once
/** \file Frame.h
 * One RGB-D frame as the rest of keygrid sees it, whatever the source.
 */
#include <keygrid/core/RgbdCamera.h>
#include <opencv2/core/mat.hpp>

#include <cstddef>

namespace keygrid::core
{
/** An RGB-D frame: images as captured (distortion is described by `camera`, not removed),
 * depth registered to the colour image and converted to metres. */
struct Frame
{
	/** Position in the source sequence, 0-based. */
	std::size_t index{0};
	/** Capture time [s] (UNIX epoch for TUM / MRPT timestamps). */
	double timestamp{0.0};
	/** 8-bit grey image (CV_8UC1). */
	cv::Mat grey;
	/** Colour image (CV_8UC3, BGR) when the source has one; may be empty. */
	cv::Mat colour;
	/** Depth along the optical axis [m] (CV_32FC1), 0 where invalid. */
	cv::Mat depth;
	/** Raw depth (CV_16UC1) with depth = raw * camera.depthUnits, when the source keeps it. */
	cv::Mat depthRaw;
	/** Intrinsics, distortion and depth unit of this frame. */
	RgbdCamera camera;

	bool hasDepth() const { return !depth.empty(); }
	bool hasImage() const { return !grey.empty(); }
};

/** Converts a raw depth image (CV_16UC1) to metres (CV_32FC1): depth = raw * units.
 * The one place where raw depth becomes metres, so every path gives the same bits. */
cv::Mat depthRawToMetres(const cv::Mat& depthRaw, float units);

}  // namespace keygrid::core
