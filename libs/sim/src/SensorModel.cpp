#include "IniHelpers.h"
#include "Parallel.h"

#include <keygrid/sim/Random.h>
#include <keygrid/sim/SensorModel.h>
#include <mrpt/config/CConfigFileBase.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace keygrid::sim
{
void SensorOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	noise = ini::readBool(c, s, "noise", noise);
	sigmaA = ini::readDouble(c, s, "sigma_a", sigmaA, 0, 1);
	sigmaB = ini::readDouble(c, s, "sigma_b", sigmaB, 0, 1);
	sigmaZ0 = ini::readDouble(c, s, "sigma_z0", sigmaZ0, 0, 100);
	quantiseDisparity = ini::readBool(c, s, "quantise_disparity", quantiseDisparity);
	baseline = ini::readDouble(c, s, "baseline", baseline, 1e-3, 10);
	disparitySubpixel = ini::readDouble(c, s, "disparity_subpixel", disparitySubpixel, 1, 1024);
	minRange = ini::readDouble(c, s, "min_range", minRange, 0, 1000);
	maxRange = ini::readDouble(c, s, "max_range", maxRange, 0, 1000);
	maxIncidenceDeg = ini::readDouble(c, s, "max_incidence_deg", maxIncidenceDeg, 0, 90);
	dropoutProbability = ini::readDouble(c, s, "dropout_probability", dropoutProbability, 0, 1);
	imageNoiseSigma = ini::readDouble(c, s, "image_noise_sigma", imageNoiseSigma, 0, 100);
	disparityDistortion =
		ini::readDouble(c, s, "disparity_distortion", disparityDistortion, -5, 5);
	rollingShutterReadout = ini::readDouble(c, s, "rolling_shutter_readout", rollingShutterReadout, 0, 1);
	try
	{
		validate();
	}
	catch (const std::invalid_argument& e)
	{
		throw std::invalid_argument("[" + s + "] " + e.what());
	}
}

void SensorOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	c.write(s, "noise", noise ? "true" : "false");
	c.write(s, "sigma_a", sigmaA);
	c.write(s, "sigma_b", sigmaB);
	c.write(s, "sigma_z0", sigmaZ0);
	c.write(s, "quantise_disparity", quantiseDisparity ? "true" : "false");
	c.write(s, "baseline", baseline);
	c.write(s, "disparity_subpixel", disparitySubpixel);
	c.write(s, "min_range", minRange);
	c.write(s, "max_range", maxRange);
	c.write(s, "max_incidence_deg", maxIncidenceDeg);
	c.write(s, "dropout_probability", dropoutProbability);
	c.write(s, "image_noise_sigma", imageNoiseSigma);
	c.write(s, "disparity_distortion", disparityDistortion);
	c.write(s, "rolling_shutter_readout", rollingShutterReadout);
}

void SensorOptions::validate() const
{
	if (!(minRange < maxRange))
		throw std::invalid_argument(
			"min_range = " + std::to_string(minRange) +
			" must be < max_range = " + std::to_string(maxRange));
	if (!(sigmaA >= 0 && sigmaB >= 0)) throw std::invalid_argument("sigma_a, sigma_b must be >= 0");
	if (!(maxIncidenceDeg > 0 && maxIncidenceDeg <= 90))
		throw std::invalid_argument(
			"max_incidence_deg = " + std::to_string(maxIncidenceDeg) + " must be in (0, 90]");
}

SensorModel::SensorModel(
	const SensorOptions& opts, double focalPx, std::uint64_t seed, unsigned threads)
	: m_opts(opts), m_fB(std::abs(focalPx) * opts.baseline), m_seed(seed), m_threads(threads)
{
	m_opts.validate();
	m_cosMin = opts.maxIncidenceDeg >= 90 ? 0.0 : std::cos(opts.maxIncidenceDeg * M_PI / 180.0);
}

double SensorModel::sigma(double z) const
{
	const double dz = z - m_opts.sigmaZ0;
	return m_opts.sigmaA + m_opts.sigmaB * dz * dz;
}

double SensorModel::quantise(double z) const
{
	const double s = m_opts.disparitySubpixel;
	const double steps = std::round(s * m_fB / z);
	return steps > 0 ? m_fB * s / steps : 0.0;
}

double SensorModel::distort(double z, double rho2) const
{
	const double d = m_fB / z - m_opts.disparityDistortion * rho2;
	return d > 0 ? m_fB / d : 0.0;
}

namespace
{
/** The 2^16 standard-normal quantiles at (k + 0.5) / 2^16 (inverse CDF by Newton on erfc).
 * Indexing it with a uniform 16-bit number draws from N(0, 1) discretised to 65536 levels
 * (tails cut at 4.17 sigma); one lookup per draw keeps the sensor model cheaper than the
 * renderer. */
const std::vector<float>& gaussianTable()
{
	static const std::vector<float> table = [] {
		constexpr int n = 1 << 16;
		std::vector<float> t(n);
		for (int k = 0; k < n / 2; k++)
		{
			// Solve Phi(x) = p for the lower half; Phi(x) = erfc(-x / sqrt 2) / 2.
			const double p = (k + 0.5) / n;
			double x = -std::sqrt(-2.0 * std::log(p));  // tail start, refined by Newton
			for (int it = 0; it < 60; it++)
			{
				const double f = 0.5 * std::erfc(-x / M_SQRT2) - p;
				const double d = std::exp(-0.5 * x * x) / std::sqrt(2.0 * M_PI);
				const double step = f / d;
				x -= step;
				if (std::abs(step) < 1e-13) break;
			}
			t[k] = static_cast<float>(x);
			t[n - 1 - k] = static_cast<float>(-x);
		}
		return t;
	}();
	return table;
}
}  // namespace

void SensorModel::apply(
	std::size_t frameIndex, const cv::Mat& trueDepth, const cv::Mat& cosIncidence,
	cv::Mat& depthOut, cv::Mat& colour) const
{
	CV_Assert(trueDepth.type() == CV_32FC1 && cosIncidence.type() == CV_32FC1);
	CV_Assert(colour.type() == CV_8UC3 && colour.size() == trueDepth.size());
	depthOut.create(trueDepth.size(), CV_32FC1);
	const int W = trueDepth.cols;
	const std::uint64_t frameKey = hashKey(m_seed, 0x5E5E, frameIndex);
	const bool noisy = m_opts.noise;
	const float* gauss = gaussianTable().data();
	// Dropout when the 16-bit uniform falls below p * 2^16.
	const std::uint64_t dropBelow =
		static_cast<std::uint64_t>(std::llround(m_opts.dropoutProbability * 65536.0));
	const float imgSigma = static_cast<float>(m_opts.imageNoiseSigma);
	const bool distorted = m_opts.disparityDistortion != 0;
	const double cx = 0.5 * (W - 1), cy = 0.5 * (trueDepth.rows - 1);
	const double invHalfDiag2 = 1.0 / (cx * cx + cy * cy);
	parallelRows(trueDepth.rows, m_threads, [&](int r0, int r1) {
		for (int y = r0; y < r1; y++)
		{
			const float* zt = trueDepth.ptr<float>(y);
			const float* ci = cosIncidence.ptr<float>(y);
			float* zo = depthOut.ptr<float>(y);
			auto* px = colour.ptr<cv::Vec3b>(y);
			for (int x = 0; x < W; x++)
			{
				// One 64-bit hash per pixel feeds four 16-bit draws: depth noise, dropout, and
				// two colour channels; a second mix gives the third channel.
				const std::uint64_t h = mix64(
					frameKey ^ (static_cast<std::uint64_t>(y) * W + x) * 0x9E3779B97F4A7C15ULL);
				double z = zt[x];
				const bool valid =
					z > 0 && z >= m_opts.minRange && z <= m_opts.maxRange && ci[x] >= m_cosMin;
				if (valid && distorted)
					z = distort(z, ((x - cx) * (x - cx) + (y - cy) * (y - cy)) * invHalfDiag2);
				if (!valid || !(z > 0))
					z = 0;
				else if (noisy)
				{
					if (((h >> 16) & 0xFFFF) < dropBelow)
						z = 0;
					else
					{
						z += sigma(z) * gauss[h & 0xFFFF];
						if (m_opts.quantiseDisparity) z = quantise(z);
						if (!(z > 0)) z = 0;
					}
				}
				zo[x] = static_cast<float>(z);
				if (noisy && imgSigma > 0)
				{
					const std::uint64_t h2 = mix64(h);
					const float n[3] = {
						gauss[(h >> 32) & 0xFFFF], gauss[(h >> 48) & 0xFFFF], gauss[h2 & 0xFFFF]};
					for (int k = 0; k < 3; k++)
						px[x][k] = cv::saturate_cast<std::uint8_t>(px[x][k] + imgSigma * n[k]);
				}
			}
		}
	});
}

}  // namespace keygrid::sim
