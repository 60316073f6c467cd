#pragma once
/** \file Frame.h
 * One RGB-D frame as the rest of keygrid sees it, whatever the source.
 */
#include <keygrid/core/RgbdCamera.h>
#include <opencv2/core/mat.hpp>

#include <cstddef>

namespace keygrid::core
{
/** Whether a frame source delivers depth. Ignore reads the images alone (monocular input):
 * depth stored in the input is neither loaded nor decoded, and an input without depth is
 * accepted. */
enum class DepthUse
{
	Use,
	Ignore
};

/** An RGB-D frame: images as captured (distortion is described by `camera`, not removed),
 * depth registered to the colour image and converted to metres. An image-only frame
 * (DepthUse::Ignore, monocular input) has empty depth and depthRaw. */
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

/** Sets out.grey (and out.colour for a 3-channel BGR image; released for a 1-channel one)
 * from an image as captured. Returns false, leaving `out` as it was, for another channel
 * count. */
bool setFrameImages(const cv::Mat& image, Frame& out);

/** Fills `out` as an image-only frame (monocular input): images as setFrameImages, timestamp
 * and camera; depth and depthRaw released. Returns false, leaving `out` as it was, for an
 * image of another channel count. */
bool setImageOnlyFrame(const cv::Mat& image, double timestamp, const RgbdCamera& camera, Frame& out);

/** Converts a raw depth image (CV_16UC1) to metres (CV_32FC1): depth = raw * units.
 * The one place where raw depth becomes metres, so every path gives the same bits. */
cv::Mat depthRawToMetres(const cv::Mat& depthRaw, float units);

}  // namespace keygrid::core
