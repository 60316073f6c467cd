#pragma once
/** \file RgbdObservation.h
 * Frame <-> mrpt::obs::CObservation3DRangeScan, in the layout keygrid-tum2rawlog and
 * keygrid-sim write and every frame source reads (ImageObservation.h: the monocular
 * counterpart, CObservationImage).
 */
#include <keygrid/core/Frame.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include <string>

namespace keygrid::core
{
/** How a Frame is written as an observation. */
struct ObservationWriteOptions
{
	/** Sensor label stored in the observation (Default: "KINECT") */
	std::string sensorLabel{"KINECT"};
	/** Maximum sensor range [m] stored in CObservation3DRangeScan::maxRange (Default: 10 m) */
	float maxRange{10.0f};
	/** Store the colour image when the frame has one, else the grey one (Default: true) */
	bool preferColour{true};
};

/** Builds a CObservation3DRangeScan from a frame: range image = the frame's raw depth
 * (depthRaw if present, else round(depth / depthUnits)) with rangeUnits = camera.depthUnits,
 * intensity image, cameraParams == cameraParamsIntensity (registered depth), and
 * relativePoseIntensityWRTDepth = T_depth_cam(). Throws std::invalid_argument on
 * inconsistent sizes or depth beyond the uint16 range. */
mrpt::obs::CObservation3DRangeScan::Ptr makeRgbdObservation(
	const Frame& frame, const ObservationWriteOptions& opts = {});

/** Fills `out` from an observation (which must be loaded if it has external images).
 * Returns false and sets *why when the observation cannot be a frame (no range image,
 * no intensity image, size mismatch, non-coinciding cameras). */
bool frameFromObservation(
	const mrpt::obs::CObservation3DRangeScan& obs, Frame& out, std::string* why = nullptr);

/** The image-only frame of an RGB-D observation (depth ignored: monocular input): the
 * intensity image, its camera (cameraParamsIntensity, as frameFromObservation gives it) and
 * the timestamp; depth and depthRaw empty. Only the intensity image needs to be loaded, and
 * an observation without a range image is accepted. Returns false and sets *why when there
 * is no usable intensity image or camera. */
bool imageFrameFromObservation(
	const mrpt::obs::CObservation3DRangeScan& obs, Frame& out, std::string* why = nullptr);

}  // namespace keygrid::core
