#include <keygrid/core/DepthRegistration.h>
#include <keygrid/core/FrameConventions.h>
#include <keygrid/core/RgbdObservation.h>
#include <mrpt/system/datetime.h>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace keygrid::core
{
cv::Mat depthRawToMetres(const cv::Mat& raw, float units)
{
	CV_Assert(raw.type() == CV_16UC1);
	cv::Mat m(raw.rows, raw.cols, CV_32FC1);
	for (int r = 0; r < raw.rows; r++)
	{
		const auto* in = raw.ptr<uint16_t>(r);
		auto* out = m.ptr<float>(r);
		for (int c = 0; c < raw.cols; c++) out[c] = static_cast<float>(in[c]) * units;
	}
	return m;
}

namespace
{
cv::Mat rawFromMetres(const cv::Mat& depth, float units)
{
	cv::Mat raw(depth.rows, depth.cols, CV_16UC1);
	for (int r = 0; r < depth.rows; r++)
	{
		const float* in = depth.ptr<float>(r);
		auto* out = raw.ptr<uint16_t>(r);
		for (int c = 0; c < depth.cols; c++)
		{
			const float d = in[c];
			if (!(d > 0) || !std::isfinite(d))
			{
				out[c] = 0;
				continue;
			}
			const double q = std::round(static_cast<double>(d) / units);
			if (q > std::numeric_limits<uint16_t>::max())
				throw std::invalid_argument(
					"depth " + std::to_string(d) + " m does not fit uint16 at depth_units " +
					std::to_string(units));
			out[c] = static_cast<uint16_t>(q);
		}
	}
	return raw;
}

/** The camera of the intensity image, checked against it. Empty string when usable, else why
 * not: calibrations that disagree with the image (or hold NaN) would index outside it later. */
std::string intensityCamera(const mrpt::obs::CObservation3DRangeScan& obs, float units, RgbdCamera& cam)
{
	cam = RgbdCamera::FromTCamera(obs.cameraParamsIntensity, units);
	std::string err;
	if (!cam.isValid(&err)) return "invalid intensity camera parameters: " + err;
	if (cam.width != obs.intensityImage.getWidth() || cam.height != obs.intensityImage.getHeight())
		return "intensity camera parameters are for " + std::to_string(cam.width) + "x" +
			std::to_string(cam.height) + " but the image is " + std::to_string(obs.intensityImage.getWidth()) +
			"x" + std::to_string(obs.intensityImage.getHeight());
	return {};
}
}  // namespace

mrpt::obs::CObservation3DRangeScan::Ptr makeRgbdObservation(
	const Frame& f, const ObservationWriteOptions& opts)
{
	const cv::Mat& img = (opts.preferColour && !f.colour.empty()) ? f.colour : f.grey;
	if (img.empty()) throw std::invalid_argument("frame " + std::to_string(f.index) + " has no image");
	const cv::Mat raw = !f.depthRaw.empty() ? f.depthRaw
		: !f.depth.empty()					? rawFromMetres(f.depth, f.camera.depthUnits)
											: cv::Mat();
	if (raw.empty()) throw std::invalid_argument("frame " + std::to_string(f.index) + " has no depth");
	if (raw.type() != CV_16UC1)
		throw std::invalid_argument("frame " + std::to_string(f.index) + ": raw depth must be CV_16UC1");
	if (raw.size() != img.size())
		throw std::invalid_argument(
			"frame " + std::to_string(f.index) + ": depth " + std::to_string(raw.cols) + "x" +
			std::to_string(raw.rows) + " and image " + std::to_string(img.cols) + "x" +
			std::to_string(img.rows) + " differ in size");

	auto obs = mrpt::obs::CObservation3DRangeScan::Create();
	obs->sensorLabel = opts.sensorLabel;
	obs->timestamp = mrpt::Clock::fromDouble(f.timestamp);
	obs->hasRangeImage = true;
	obs->range_is_depth = true;
	obs->rangeUnits = f.camera.depthUnits;
	obs->rangeImage.resize(raw.rows, raw.cols);
	for (int r = 0; r < raw.rows; r++)
	{
		const auto* in = raw.ptr<uint16_t>(r);
		for (int c = 0; c < raw.cols; c++) obs->rangeImage(r, c) = in[c];
	}
	obs->hasIntensityImage = true;
	obs->intensityImage = mrpt::img::CImage(img, mrpt::img::DEEP_COPY);
	RgbdCamera cam = f.camera;
	cam.width = static_cast<unsigned>(img.cols);
	cam.height = static_cast<unsigned>(img.rows);
	obs->cameraParams = cam.toTCamera();
	obs->cameraParamsIntensity = obs->cameraParams;
	obs->relativePoseIntensityWRTDepth = T_depth_cam();
	obs->sensorPose = mrpt::poses::CPose3D();
	obs->maxRange = opts.maxRange;
	return obs;
}

bool frameFromObservation(
	const mrpt::obs::CObservation3DRangeScan& obs, Frame& out, std::string* why)
{
	auto fail = [&](const std::string& msg) {
		if (why) *why = msg;
		return false;
	};
	if (!obs.hasRangeImage || obs.rangeImage.rows() == 0) return fail("observation has no range image");
	if (!obs.hasIntensityImage || obs.intensityImage.isEmpty())
		return fail("observation has no intensity image");
	if (!obs.range_is_depth) return fail("range image holds 3D ranges, not depth (range_is_depth=false)");
	if (!(obs.rangeUnits > 0) || !std::isfinite(obs.rangeUnits))
		return fail("invalid rangeUnits " + std::to_string(obs.rangeUnits));
	const int rows = static_cast<int>(obs.rangeImage.rows());
	const int cols = static_cast<int>(obs.rangeImage.cols());
	if (obs.doDepthAndIntensityCamerasCoincide() &&
		(static_cast<int>(obs.intensityImage.getWidth()) != cols ||
		 static_cast<int>(obs.intensityImage.getHeight()) != rows))
		return fail(
			"intensity image " + std::to_string(obs.intensityImage.getWidth()) + "x" +
			std::to_string(obs.intensityImage.getHeight()) + " and range image " +
			std::to_string(cols) + "x" + std::to_string(rows) + " differ in size");

	RgbdCamera intensityCam;
	std::string err = intensityCamera(obs, obs.rangeUnits, intensityCam);
	if (!err.empty()) return fail(err);
	const bool registered = obs.doDepthAndIntensityCamerasCoincide() && obs.cameraParams == obs.cameraParamsIntensity;
	if (!registered)
	{
		const RgbdCamera depthCam = RgbdCamera::FromTCamera(obs.cameraParams, obs.rangeUnits);
		// (Its width/height may differ from the range image's: Kinect calibrations often say 640x488.)
		if (!depthCam.isValid(&err)) return fail("invalid depth camera parameters: " + err);
		const auto H = obs.relativePoseIntensityWRTDepth.getHomogeneousMatrixVal<mrpt::math::CMatrixDouble44>();
		for (int r = 0; r < 3; r++)
			for (int c = 0; c < 4; c++)
				if (!std::isfinite(H(r, c))) return fail("relativePoseIntensityWRTDepth is not finite");
	}

	out.timestamp = mrpt::Clock::toDouble(obs.timestamp);
	out.camera = intensityCam;
	out.depthRaw.create(rows, cols, CV_16UC1);
	for (int r = 0; r < rows; r++)
	{
		auto* o = out.depthRaw.ptr<uint16_t>(r);
		for (int c = 0; c < cols; c++) o[c] = obs.rangeImage(r, c);
	}
	// Unregistered sensors (raw Kinect): bring depth into the colour camera, where the frame lives.
	if (!registered)
		out.depthRaw = registerDepthToIntensity(
			out.depthRaw, obs.rangeUnits, obs.cameraParams, obs.cameraParamsIntensity,
			obs.relativePoseIntensityWRTDepth);
	out.depth = depthRawToMetres(out.depthRaw, obs.rangeUnits);
	const cv::Mat& img = obs.intensityImage.asCvMatRef();
	if (!setFrameImages(img, out)) return fail("intensity image has " + std::to_string(img.channels()) + " channels");
	return true;
}

bool imageFrameFromObservation(
	const mrpt::obs::CObservation3DRangeScan& obs, Frame& out, std::string* why)
{
	// The depth unit only completes the camera description: the one stored when valid, so that
	// the camera equals the RGB-D frame's, else the default.
	const float units = obs.rangeUnits > 0 && std::isfinite(obs.rangeUnits) ? obs.rangeUnits : RgbdCamera{}.depthUnits;
	RgbdCamera cam;
	std::string err = !obs.hasIntensityImage || obs.intensityImage.isEmpty() ? "observation has no intensity image"
																			  : intensityCamera(obs, units, cam);
	if (err.empty())
	{
		const cv::Mat& img = obs.intensityImage.asCvMatRef();
		if (!setImageOnlyFrame(img, mrpt::Clock::toDouble(obs.timestamp), cam, out))
			err = "intensity image has " + std::to_string(img.channels()) + " channels";
	}
	if (why && !err.empty()) *why = err;
	return err.empty();
}

}  // namespace keygrid::core
