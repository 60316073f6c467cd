#pragma once
/** \file InverseSensorModel.h
 * The inverse sensor model (ISM) of Lu & Wang, "Real-time grid map construction based on
 * ORB-SLAM2" (2018), after Dia et al. (2017): an ideal ISM that is occupied over a band of
 * width L around the measured range, convolved with Gaussian range noise, in closed form.
 *
 * All functions are pure; the grid map (CISMOccupancyGrid2D) only evaluates them per cell.
 */
#include <cstdint>
#include <string>

namespace keygrid::maps
{
/** Shape of the ideal ISM g(r) for one measured range z (probabilities of "occupied"). */
struct IsmShape
{
	/** Ideal-model occupancy before the band, r < z - L/2 (Default: 0.30) */
	double pFree{0.30};
	/** Ideal-model occupancy inside the band |r - z| <= L/2 (Default: 0.90) */
	double pOccupied{0.90};
	/** Ideal-model occupancy behind the band, r > z + L/2: unknown = the prior (Default: 0.5) */
	double pPrior{0.5};
	/** Band width L [m] (Default: 0.0707 m = diagonal of a 5 cm cell) */
	double bandWidth{0.0707106781};

	/** Throws std::invalid_argument naming the offending field unless
	 * 0 < pFree < pPrior < pOccupied < 1 and bandWidth > 0. */
	void validate() const;
};

/** Ideal ISM g(r): pFree for r < z - L/2, pOccupied for z - L/2 <= r <= z + L/2, pPrior beyond.
 * \param r distance of the evaluated cell from the sensor along the ray [m]
 * \param z measured range [m] */
double idealIsm(double r, double z, const IsmShape& shape);

/** Practical ISM = ideal ISM convolved with N(0, sigma^2) range noise, closed form with erf
 * (derivation in InverseSensorModel.cpp). sigma <= 0 returns the ideal model. */
double practicalIsm(double r, double z, double sigma, const IsmShape& shape);

/** log(p / (1 - p)) */
double logit(double p);
/** 1 / (1 + exp(-l)) */
double logistic(double l);

/** How the range noise sigma depends on the measured depth. */
enum class RangeNoiseModel : uint8_t
{
	/** sigma = sigmaConstant for every range */
	Constant = 0,
	/** Kinect v1 axial noise (Nguyen, Izadi, Lovell 2012):
	 * sigma(z) = 0.0012 + 0.0019 (z - 0.4)^2 [m], z = depth along the optical axis [m] */
	Kinect = 1
};

/** "constant" / "kinect" <-> enum; throws std::invalid_argument on an unknown name. */
RangeNoiseModel rangeNoiseModelFromString(const std::string& name);
std::string toString(RangeNoiseModel m);

/** Range noise sigma [m] at depth z [m] for the chosen model, never below 1e-4 m. */
double rangeSigma(RangeNoiseModel model, double sigmaConstant, double z);

}  // namespace keygrid::maps
