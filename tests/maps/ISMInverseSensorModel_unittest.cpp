/** The practical ISM against an independent numerical convolution of the ideal model with a
 * Gaussian, and the paper's qualitative results (Sec. 4.1, 4.2). */
#include <keygrid/maps/InverseSensorModel.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace keygrid::maps;

namespace
{
/** (g * f)(r) = int g(tau) N(r - tau; 0, sigma^2) dtau by composite Simpson over each smooth
 * piece of g (so the band edges are integration nodes), tau in r +- 12 sigma. Independent of
 * erf: the Gaussian density is evaluated directly. */
double numericConvolution(double r, double z, double sigma, const IsmShape& s)
{
	const double lo = r - 12 * sigma, hi = r + 12 * sigma;
	const double a = z - 0.5 * s.bandWidth, b = z + 0.5 * s.bandWidth;
	auto f = [&](double tau) {
		const double u = (r - tau) / sigma;
		return idealIsm(tau, z, s) * std::exp(-0.5 * u * u) / (sigma * std::sqrt(2 * M_PI));
	};
	auto simpson = [&](double x0, double x1) {
		if (x1 <= x0) return 0.0;
		const int n = 2000;  // even
		const double h = (x1 - x0) / n;
		// Evaluate strictly inside the piece: g is constant there (edges shifted by 1e-12).
		auto fi = [&](int i) {
			double t = x0 + i * h;
			if (i == 0) t += 1e-12;
			if (i == n) t -= 1e-12;
			return f(t);
		};
		double acc = fi(0) + fi(n);
		for (int i = 1; i < n; i++) acc += (i % 2 ? 4.0 : 2.0) * fi(i);
		return acc * h / 3.0;
	};
	const double p1 = std::min(std::max(a, lo), hi), p2 = std::min(std::max(b, lo), hi);
	// Mass outside r +- 12 sigma (< 1e-32) is dropped.
	return simpson(lo, p1) + simpson(p1, p2) + simpson(p2, hi);
}

double peak(double z, double sigma, const IsmShape& s) { return practicalIsm(z, z, sigma, s); }
}  // namespace

TEST(ISMInverseSensorModel, ClosedFormMatchesNumericalConvolution)
{
	IsmShape s;
	for (double L : {0.02, 0.0707, 0.2})
		for (double sigma : {0.002, 0.01, 0.03, 0.1})
			for (double z : {0.8, 2.5})
			{
				s.bandWidth = L;
				for (double r = z - 0.4; r <= z + 0.4; r += 0.0123)
				{
					const double closed = practicalIsm(r, z, sigma, s);
					const double numeric = numericConvolution(r, z, sigma, s);
					ASSERT_NEAR(closed, numeric, 1e-6) << "L=" << L << " sigma=" << sigma << " z=" << z << " r=" << r;
				}
			}
}

TEST(ISMInverseSensorModel, LimitsAndIdealModel)
{
	const IsmShape s;
	EXPECT_DOUBLE_EQ(idealIsm(1.0, 2.0, s), s.pFree);
	EXPECT_DOUBLE_EQ(idealIsm(2.0, 2.0, s), s.pOccupied);
	EXPECT_DOUBLE_EQ(idealIsm(3.0, 2.0, s), s.pPrior);
	// Far before / after the band the practical model is the ideal one.
	EXPECT_NEAR(practicalIsm(1.0, 2.0, 0.01, s), s.pFree, 1e-12);
	EXPECT_NEAR(practicalIsm(3.0, 2.0, 0.01, s), s.pPrior, 1e-12);
	// sigma -> 0 gives the ideal model.
	EXPECT_DOUBLE_EQ(practicalIsm(2.0, 2.0, 0.0, s), s.pOccupied);
	// At a band edge exactly half of the noise mass falls in the band.
	const double a = 2.0 - 0.5 * s.bandWidth;
	EXPECT_NEAR(practicalIsm(a, 2.0, 1e-5, s), 0.5 * (s.pFree + s.pOccupied), 1e-9);
}

TEST(ISMInverseSensorModel, LargerBandMarksMoreCellsOccupied)
{
	// Paper Fig. 3: fixed z and sigma, growing L raises the occupancy near z and widens the
	// region above the occupied threshold.
	const double z = 2.0, sigma = 0.02, res = 0.01, thr = 0.65;
	int prevCount = -1;
	double prevPeak = 0;
	for (double L : {0.02, 0.05, 0.0707, 0.15, 0.3})
	{
		IsmShape s;
		s.bandWidth = L;
		int count = 0;
		for (double r = z - 1.0; r <= z + 1.0; r += res)
			if (practicalIsm(r, z, sigma, s) >= thr) count++;
		const double pk = peak(z, sigma, s);
		EXPECT_GT(count, prevCount) << "L=" << L;
		EXPECT_GT(pk, prevPeak) << "L=" << L;
		prevCount = count;
		prevPeak = pk;
	}
}

TEST(ISMInverseSensorModel, LargerSigmaLowersPeakOccupancy)
{
	// Paper Fig. 4.
	IsmShape s;
	double prev = 1.0;
	for (double sigma : {0.005, 0.01, 0.02, 0.05, 0.1})
	{
		const double pk = peak(2.0, sigma, s);
		EXPECT_LT(pk, prev) << "sigma=" << sigma;
		EXPECT_GT(pk, s.pPrior - 1e-12);
		prev = pk;
	}
}

TEST(ISMInverseSensorModel, LongerRangeLowersCertainty)
{
	// Paper Fig. 5 with the range-dependent Kinect noise: the peak occupancy falls with z
	// (2 cm band, so that the noise is not negligible against L/2 already at 1 m).
	IsmShape s;
	s.bandWidth = 0.02;
	double prev = 1.0;
	for (double z : {1.0, 1.5, 2.5, 3.5, 4.5})
	{
		const double sigma = rangeSigma(RangeNoiseModel::Kinect, 0.0, z);
		const double pk = peak(z, sigma, s);
		EXPECT_LT(pk, prev) << "z=" << z;
		prev = pk;
	}
	EXPECT_NEAR(rangeSigma(RangeNoiseModel::Kinect, 0.0, 2.4), 0.0012 + 0.0019 * 4.0, 1e-15);
	EXPECT_DOUBLE_EQ(rangeSigma(RangeNoiseModel::Constant, 0.03, 4.0), 0.03);
}

TEST(ISMInverseSensorModel, ValidationNamesTheField)
{
	IsmShape s;
	s.pOccupied = 0.4;
	try
	{
		s.validate();
		FAIL() << "expected an exception";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("pOccupied"), std::string::npos) << e.what();
	}
	EXPECT_THROW(rangeNoiseModelFromString("laser"), std::invalid_argument);
	EXPECT_EQ(rangeNoiseModelFromString("Kinect"), RangeNoiseModel::Kinect);
}
