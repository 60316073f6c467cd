#include <keygrid/maps/InverseSensorModel.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace keygrid::maps
{
void IsmShape::validate() const
{
	auto bad = [](const std::string& key, double v, const std::string& why) {
		throw std::invalid_argument(
			"ISM option '" + key + "' = " + std::to_string(v) + " is invalid: " + why);
	};
	if (!(pFree > 0.0 && pFree < 1.0)) bad("pFree", pFree, "must be in (0, 1)");
	if (!(pOccupied > 0.0 && pOccupied < 1.0)) bad("pOccupied", pOccupied, "must be in (0, 1)");
	if (!(pPrior > 0.0 && pPrior < 1.0)) bad("pPrior", pPrior, "must be in (0, 1)");
	if (!(pFree < pPrior)) bad("pFree", pFree, "must be below pPrior");
	if (!(pOccupied > pPrior)) bad("pOccupied", pOccupied, "must be above pPrior");
	if (!(bandWidth > 0.0) || !std::isfinite(bandWidth))
		bad("bandWidth", bandWidth, "must be a positive length [m]");
}

double idealIsm(double r, double z, const IsmShape& s)
{
	const double a = z - 0.5 * s.bandWidth;
	const double b = z + 0.5 * s.bandWidth;
	if (r < a) return s.pFree;
	if (r <= b) return s.pOccupied;
	return s.pPrior;
}

/* Practical ISM in closed form.
 *
 * The ideal model is piecewise constant in r with the band [a, b], a = z - L/2, b = z + L/2:
 *     g(r) = pF  (r < a),   pO  (a <= r <= b),   p0  (r > b).
 * The range noise is f(u) = N(u; 0, sigma^2), symmetric, with CDF
 *     Phi(x) = 1/2 (1 + erf(x / (sigma sqrt 2))).
 * The convolution splits over the three pieces (the paper's "piecewise convolution"):
 *     (g * f)(r) = int g(tau) f(r - tau) dtau
 *                = pF int_{-inf}^{a} f(r - tau) dtau + pO int_{a}^{b} f(r - tau) dtau
 *                  + p0 int_{b}^{inf} f(r - tau) dtau.
 * With u = tau - r and f symmetric, int_{lo}^{hi} f(r - tau) dtau = Phi(hi - r) - Phi(lo - r).
 * Writing F(hi, lo) = 1/2 [erf((hi - r)/(sigma sqrt 2)) - erf((lo - r)/(sigma sqrt 2))]
 * for that integral (the paper's F(a, b) over the interval [b, a]):
 *     (g * f)(r) = pF F(a, -inf) + pO F(b, a) + p0 F(inf, b)
 *                = pF Ea + pO (Eb - Ea) + p0 (1 - Eb),   Ex = Phi(x - r).
 * The three weights are non-negative and sum to one, so the result stays in [pF, pO] when
 * pF < p0 < pO: larger sigma spreads the occupied band and lowers its peak (paper, Fig. 4),
 * larger L widens the band (Fig. 3).
 */
double practicalIsm(double r, double z, double sigma, const IsmShape& s)
{
	if (!(sigma > 0.0)) return idealIsm(r, z, s);
	const double a = z - 0.5 * s.bandWidth;
	const double b = z + 0.5 * s.bandWidth;
	const double k = 1.0 / (sigma * std::sqrt(2.0));
	const double Ea = 0.5 * (1.0 + std::erf((a - r) * k));
	const double Eb = 0.5 * (1.0 + std::erf((b - r) * k));
	return s.pFree * Ea + s.pOccupied * (Eb - Ea) + s.pPrior * (1.0 - Eb);
}

double logit(double p) { return std::log(p / (1.0 - p)); }
double logistic(double l) { return 1.0 / (1.0 + std::exp(-l)); }

RangeNoiseModel rangeNoiseModelFromString(const std::string& name)
{
	std::string n = name;
	std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return std::tolower(c); });
	if (n == "constant") return RangeNoiseModel::Constant;
	if (n == "kinect") return RangeNoiseModel::Kinect;
	throw std::invalid_argument(
		"range noise model '" + name + "' is unknown (expected 'constant' or 'kinect')");
}

std::string toString(RangeNoiseModel m)
{
	return m == RangeNoiseModel::Kinect ? "kinect" : "constant";
}

double rangeSigma(RangeNoiseModel model, double sigmaConstant, double z)
{
	double s = sigmaConstant;
	if (model == RangeNoiseModel::Kinect) s = 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4);
	return std::max(s, 1e-4);
}

}  // namespace keygrid::maps
