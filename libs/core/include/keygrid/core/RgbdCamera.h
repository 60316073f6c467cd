#pragma once
/** \file RgbdCamera.h
 * Intrinsics of a registered RGB-D camera (depth already aligned to the colour image, as in
 * TUM RGB-D, ICL-NUIM and Kinect/OpenNI2 with registration on) and the depth unit.
 *
 * Two camera types, on purpose: this one is the sensor as configured and recorded (size,
 * distortion, depth unit, name; INI and MRPT TCamera I/O); core::PinholeIntrinsics is the model
 * of the undistorted image alone, which back-projection and the frontend's costs need (four
 * doubles, copied into every cost functor). pinhole() is the one conversion.
 */
#include <keygrid/core/PinholeIntrinsics.h>
#include <mrpt/img/TCamera.h>

#include <array>
#include <string>

namespace mrpt::config
{
class CConfigFileBase;
}

namespace keygrid::core
{
/** Pinhole camera with Brown-Conrady (plumb-bob) distortion, depth registered to colour. */
struct RgbdCamera
{
	/** Preset or user-facing name, e.g. "fr1" (Default: "kinect") */
	std::string name{"kinect"};
	/** Image width [px] (Default: 640) */
	unsigned int width{640};
	/** Image height [px] (Default: 480) */
	unsigned int height{480};
	/** Focal lengths [px] (Default: 525, the Kinect factory value) */
	double fx{525.0}, fy{525.0};
	/** Principal point [px] (Default: 319.5, 239.5) */
	double cx{319.5}, cy{239.5};
	/** Distortion k1 k2 p1 p2 k3, OpenCV order (Default: all zero) */
	std::array<double, 5> dist{{0, 0, 0, 0, 0}};
	/** Metres per raw depth unit (Default: 0.0002 = 1/5000, the TUM/ICL PNG scale) */
	float depthUnits{0.0002f};

	bool hasDistortion() const;
	/** The pinhole model of the undistorted image (back-projection, rays): the one conversion. */
	PinholeIntrinsics pinhole() const { return {fx, fy, cx, cy}; }

	/** Named presets: "kinect", "fr1", "fr2", "fr3", "icl" (TUM / ICL-NUIM calibrations).
	 * Throws std::invalid_argument naming the preset when unknown. */
	static RgbdCamera Preset(const std::string& presetName);

	/** Loads keys fx fy cx cy width height k1 k2 p1 p2 k3 depth_units from `section`.
	 * Missing keys keep their current value; invalid values throw naming the key. */
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section);
	void saveToConfigFile(mrpt::config::CConfigFileBase& cfg, const std::string& section) const;
	/** Reads `--camera` values: a preset name or the path of an INI file with a [camera] section. */
	static RgbdCamera FromPresetOrFile(const std::string& presetOrIniPath);

	/** Checks ranges; on failure writes the reason to *error (when given) and returns false. */
	bool isValid(std::string* error = nullptr) const;

	/** To/from MRPT's camera description (plumb_bob distortion when any coefficient is set). */
	mrpt::img::TCamera toTCamera() const;
	static RgbdCamera FromTCamera(const mrpt::img::TCamera& cam, float depthUnits);
};

}  // namespace keygrid::core
