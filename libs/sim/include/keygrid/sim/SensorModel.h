#pragma once
/** \file SensorModel.h
 * Kinect-like corruption of a perfect rendering:
 * - axial depth noise, Gaussian with sigma(z) = a + b (z - z0)^2 (Nguyen, Izadi, Lovell 2012:
 *   a = 0.0012 m, b = 0.0019 m^-1, z0 = 0.4 m);
 * - disparity quantisation: a structured-light sensor measures disparity d = f B / z in steps of
 *   1/s pixel, so z is rounded to f B / (round(s f B / z) / s);
 * - invalid pixels (depth 0) outside [minRange, maxRange] and where the ray meets the surface
 *   at more than maxIncidence from its normal (grazing angles);
 * - random dropouts and additive Gaussian image noise;
 * - optionally, a fixed-pattern disparity distortion (off by default): an uncalibrated Kinect
 *   measures disparity with a systematic, spatially varying offset that grows towards the image
 *   borders (Smisek, Jancosek, Pajdla 2011; Herrera, Kannala, Heikkila 2012). Modelled as
 *   d' = d - k rho^2, rho = distance from the image centre / half diagonal, so
 *   z' = f B / (f B / z - k rho^2): a relative depth error k rho^2 z / (f B) that grows with
 *   range. Unlike the per-pixel noise it does not average out over many points, so it makes
 *   visual odometry drift as real Kinect data does.
 * Randomness is a pure function of (seed, frame index, pixel): same seed -> same bytes.
 */
#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <string>

namespace mrpt::config
{
class CConfigFileBase;
}

namespace keygrid::sim
{
/** The [sensor] section. */
struct SensorOptions
{
	/** Master switch of every random or quantising effect; off gives exact depth (Default: true) */
	bool noise{true};
	/** Axial depth noise sigma(z) = a + b (z - z0)^2 (Default: a = 0.0012 m, b = 0.0019 1/m,
	 * z0 = 0.4 m) */
	double sigmaA{0.0012}, sigmaB{0.0019}, sigmaZ0{0.4};
	/** Quantise depth in disparity space (Default: true, when noise is on) */
	bool quantiseDisparity{true};
	/** Projector-camera baseline [m] (Default: 0.075, Kinect v1) */
	double baseline{0.075};
	/** Disparity resolution, steps per pixel (Default: 8, i.e. 1/8 px) */
	double disparitySubpixel{8.0};
	/** Valid depth range [m] (Default: 0.4 .. 5.0); applied also with noise off */
	double minRange{0.4}, maxRange{5.0};
	/** Largest angle between the viewing ray and the surface normal that still returns depth
	 * [deg]; applied also with noise off; 90 disables (Default: 80) */
	double maxIncidenceDeg{80.0};
	/** Probability that a valid depth pixel drops out [0, 1] (Default: 0.002) */
	double dropoutProbability{0.002};
	/** Standard deviation of additive image noise [grey levels] (Default: 2.0) */
	double imageNoiseSigma{2.0};
	/** Fixed-pattern disparity distortion k [px]: the disparity offset at the image corners
	 * (see the file comment); applied also with noise off; 0 disables (Default: 0) */
	double disparityDistortion{0.0};
	/** Rolling shutter: time between the exposure of the first and the last image row [s];
	 * row y is rendered at t + (y / H - 1/2) readout from the camera's pose at that time
	 * (colour and depth alike); 0 = global shutter (Default: 0) */
	double rollingShutterReadout{0.0};

	void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section);
	void saveToConfigFile(mrpt::config::CConfigFileBase& cfg, const std::string& section) const;
	/** Throws std::invalid_argument naming the key when a value is out of range. */
	void validate() const;
};

class SensorModel
{
   public:
	/** `focalPx` is the depth camera's focal length used for disparity (the colour camera's fx:
	 * depth is registered to colour). `threads` = 0: all cores. */
	SensorModel(
		const SensorOptions& opts, double focalPx, std::uint64_t seed, unsigned threads = 0);

	/** sigma(z) [m]. */
	double sigma(double z) const;
	/** Depth rounded to the nearest representable disparity. */
	double quantise(double z) const;
	/** Depth after the fixed-pattern disparity distortion, given rho2 = rho^2, the squared
	 * normalised radius (0 at the image centre, 1 at the corners); 0 when the distorted
	 * disparity is not positive. */
	double distort(double z, double rho2) const;

	/** trueDepth (CV_32F, 0 = no surface) and cosIncidence (CV_32F, |cos| between ray and
	 * normal) -> measured depth (CV_32F, 0 = invalid). Adds image noise to colour (CV_8UC3) in
	 * place. */
	void apply(
		std::size_t frameIndex, const cv::Mat& trueDepth, const cv::Mat& cosIncidence,
		cv::Mat& depthOut, cv::Mat& colour) const;

	const SensorOptions& options() const { return m_opts; }

   private:
	SensorOptions m_opts;
	double m_fB{0};
	std::uint64_t m_seed;
	unsigned m_threads;
	double m_cosMin{0};
};

}  // namespace keygrid::sim
