#pragma once
/** \file ImageObservation.h
 * Frame <-> mrpt::obs::CObservationImage: the monocular input, as MRPT's rawlog-grabber
 * records a plain camera (CCameraSensor) and keygrid-sim writes with [output] sensor =
 * monocular.
 */
#include <keygrid/core/Frame.h>
#include <mrpt/obs/CObservationImage.h>

#include <optional>
#include <string>

namespace keygrid::core
{
/** How a Frame is written as an image observation. */
struct ImageObservationWriteOptions
{
	/** Sensor label stored in the observation (Default: "CAMERA", CCameraSensor's label) */
	std::string sensorLabel{"CAMERA"};
	/** Store the colour image when the frame has one, else the grey one (Default: true) */
	bool preferColour{true};
};

/** Builds a CObservationImage from a frame's image: image = colour (or grey), cameraParams =
 * frame.camera (sized to the image), timestamp; the camera pose on the robot is the identity.
 * Depth, if any, is not stored. Throws std::invalid_argument when the frame has no image. */
mrpt::obs::CObservationImage::Ptr makeImageObservation(
	const Frame& frame, const ImageObservationWriteOptions& opts = {});

/** Whether an observation's calibration is MRPT's default (fx = fy = 0): what CCameraSensor
 * records for cameras it has no calibration for (a USB camera through OpenCV). */
bool hasNoCalibration(const mrpt::obs::CObservationImage& obs);

/** Fills `out` with an image-only frame (depth and depthRaw empty) from an observation, which
 * must be loaded if its image is external. The camera is obs.cameraParams; when the
 * observation has no calibration (hasNoCalibration) it is `uncalibratedCamera`, if given.
 * Returns false and sets *why when the observation cannot be a frame (no image, no or an
 * invalid calibration, a calibration for another image size, 2 or 4 channels). */
bool frameFromImageObservation(
	const mrpt::obs::CObservationImage& obs, Frame& out,
	const std::optional<RgbdCamera>& uncalibratedCamera = std::nullopt, std::string* why = nullptr);

}  // namespace keygrid::core
