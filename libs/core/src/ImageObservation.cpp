#include <keygrid/core/ImageObservation.h>
#include <mrpt/system/datetime.h>

#include <stdexcept>

namespace keygrid::core
{
mrpt::obs::CObservationImage::Ptr makeImageObservation(
	const Frame& f, const ImageObservationWriteOptions& opts)
{
	const cv::Mat& img = (opts.preferColour && !f.colour.empty()) ? f.colour : f.grey;
	if (img.empty()) throw std::invalid_argument("frame " + std::to_string(f.index) + " has no image");
	auto obs = mrpt::obs::CObservationImage::Create();
	obs->sensorLabel = opts.sensorLabel;
	obs->timestamp = mrpt::Clock::fromDouble(f.timestamp);
	obs->image = mrpt::img::CImage(img, mrpt::img::DEEP_COPY);
	RgbdCamera cam = f.camera;
	cam.width = static_cast<unsigned>(img.cols);
	cam.height = static_cast<unsigned>(img.rows);
	obs->cameraParams = cam.toTCamera();
	obs->cameraPose = mrpt::poses::CPose3D();
	return obs;
}

bool hasNoCalibration(const mrpt::obs::CObservationImage& obs)
{
	return obs.cameraParams.fx() == 0 && obs.cameraParams.fy() == 0;
}

bool frameFromImageObservation(
	const mrpt::obs::CObservationImage& obs, Frame& out, const std::optional<RgbdCamera>& uncalibratedCamera,
	std::string* why)
{
	auto fail = [&](const std::string& msg) {
		if (why) *why = msg;
		return false;
	};
	if (obs.image.isEmpty()) return fail("image observation has no image");
	RgbdCamera cam;
	if (!hasNoCalibration(obs))
		cam = RgbdCamera::FromTCamera(obs.cameraParams, RgbdCamera{}.depthUnits);
	else if (uncalibratedCamera)
		cam = *uncalibratedCamera;
	else
		return fail(
			"image observation '" + obs.sensorLabel +
			"' has no calibration (fx = fy = 0, as rawlog-grabber's CCameraSensor records a USB "
			"camera): give the camera (FrameSourceOptions::camera)");
	const char* origin = hasNoCalibration(obs) ? "the given camera" : "the observation's calibration";
	std::string err;
	if (!cam.isValid(&err)) return fail(std::string("invalid camera parameters in ") + origin + ": " + err);
	const cv::Mat& img = obs.image.asCvMatRef();
	if (cam.width != static_cast<unsigned>(img.cols) || cam.height != static_cast<unsigned>(img.rows))
		return fail(
			std::string(origin) + " is for " + std::to_string(cam.width) + "x" + std::to_string(cam.height) +
			" but the image is " + std::to_string(img.cols) + "x" + std::to_string(img.rows));
	if (!setImageOnlyFrame(img, mrpt::Clock::toDouble(obs.timestamp), cam, out))
		return fail("image has " + std::to_string(img.channels()) + " channels");
	return true;
}

}  // namespace keygrid::core
