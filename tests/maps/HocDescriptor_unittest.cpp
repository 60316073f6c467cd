/** \file HocDescriptor_unittest.cpp
 * HOC bins (icosahedron faces and shells, neighbours, subdivisions), counts and weights,
 * options. Face lookups are checked against an independent ray / flat-triangle intersection. */
#include <keygrid/maps/HocGeometry.h>
#include <keygrid/maps/HocHistogram.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <set>

using keygrid::maps::HocGeometry;
using keygrid::maps::HocHistogram;
using keygrid::maps::HocOptions;

namespace
{
/** Möller–Trumbore: does the ray from the origin along d hit the flat triangle (a, b, c)? */
bool rayHitsTriangle(const Eigen::Vector3d& d, const std::array<Eigen::Vector3d, 3>& t)
{
	const Eigen::Vector3d e1 = t[1] - t[0], e2 = t[2] - t[0];
	const Eigen::Vector3d p = d.cross(e2);
	const double det = e1.dot(p);
	if (std::abs(det) < 1e-12) return false;
	const Eigen::Vector3d s = -t[0];
	const double u = s.dot(p) / det;
	if (u < -1e-12 || u > 1 + 1e-12) return false;
	const Eigen::Vector3d q = s.cross(e1);
	const double v = d.dot(q) / det;
	if (v < -1e-12 || u + v > 1 + 1e-12) return false;
	return e2.dot(q) / det > 0;
}

Eigen::Vector3d randomDirection(std::mt19937& rng)
{
	std::normal_distribution<double> n;
	Eigen::Vector3d d(n(rng), n(rng), n(rng));
	return d.normalized();
}
}  // namespace

TEST(HocGeometry, IcosahedronHas20FacesEachWithThreeMutualNeighbours)
{
	const HocGeometry g({1.0}, 0);
	ASSERT_EQ(g.numFaces(), 20);
	for (int f = 0; f < 20; f++)
	{
		const auto nb = g.faceNeighbours(f);
		const std::set<int> distinct(nb.begin(), nb.end());
		EXPECT_EQ(distinct.size(), 3u);
		const auto vf = g.faceVertices(f);
		for (int n : nb)
		{
			ASSERT_GE(n, 0);
			const auto back = g.faceNeighbours(n);
			EXPECT_NE(std::find(back.begin(), back.end(), f), back.end()) << "neighbourhood not symmetric";
			// Neighbours share exactly one edge: two vertices.
			int shared = 0;
			for (const auto& a : vf)
				for (const auto& b : g.faceVertices(n)) shared += (a - b).norm() < 1e-12;
			EXPECT_EQ(shared, 2);
			// Adjacent face centres of the regular icosahedron: angle acos(sqrt(5)/3) = 41.81 deg.
			EXPECT_NEAR(std::acos(g.faceCentre(f).dot(g.faceCentre(n))), std::acos(std::sqrt(5.0) / 3.0), 1e-9);
		}
		// Outward, counter-clockwise vertices.
		EXPECT_GT((vf[1] - vf[0]).cross(vf[2] - vf[0]).dot(g.faceCentre(f)), 0);
	}
}

TEST(HocGeometry, EveryFaceAndShellIsReachableByCamerasPlacedThere)
{
	const std::vector<double> radii{0.5, 1.5, 4.0};
	const HocGeometry g(radii, 0);
	ASSERT_EQ(g.numBins(), 60);
	const Eigen::Vector3d point(1.0, -2.0, 0.5);
	const double dists[] = {0.25, 1.0, 2.75, 9.0};
	const int shells[] = {0, 1, 2, 2};  // beyond the largest radius: outermost shell
	std::set<int> bins;
	for (int f = 0; f < 20; f++)
		for (int s = 0; s < 4; s++)
		{
			const int b = g.bin(point, point + dists[s] * g.faceCentre(f));
			EXPECT_EQ(b, shells[s] * 20 + f) << "face " << f << " distance " << dists[s];
			bins.insert(b);
		}
	EXPECT_EQ(bins.size(), 60u);
	EXPECT_EQ(g.bin(point, point), -1);
	EXPECT_EQ(g.shell(0.5), 0);  // on the sphere: inner shell
	EXPECT_EQ(g.shell(0.5000001), 1);
}

TEST(HocGeometry, FaceLookupAgreesWithRayTriangleIntersection)
{
	for (int sub : {0, 1, 2})
	{
		const HocGeometry g({1.0}, sub);
		ASSERT_EQ(g.numFaces(), 20 << (2 * sub));
		std::mt19937 rng(7 + sub);
		for (int i = 0; i < 2000; i++)
		{
			const Eigen::Vector3d d = randomDirection(rng);
			const int f = g.face(d);
			EXPECT_TRUE(rayHitsTriangle(d, g.faceVertices(f))) << "subdivision " << sub << " direction " << d.transpose();
		}
		for (int f = 0; f < g.numFaces(); f++) EXPECT_EQ(g.face(g.faceCentre(f)), f);
	}
}

TEST(HocGeometry, RegularFacesReceiveEqualShares)
{
	const HocGeometry g({1.0}, 0);
	std::mt19937 rng(3);
	std::vector<int> hits(20, 0);
	const int n = 200000;
	for (int i = 0; i < n; i++) hits[g.face(randomDirection(rng))]++;
	// Binomial(n, 1/20): sigma = sqrt(n * 0.05 * 0.95) = 97.5; 5 sigma.
	for (int h : hits) EXPECT_NEAR(h, n / 20.0, 5 * 97.5);
}

TEST(HocGeometry, RejectsBadRadiiAndSubdivisions)
{
	EXPECT_THROW(HocGeometry({}, 0), std::invalid_argument);
	EXPECT_THROW(HocGeometry({1.0, 1.0}, 0), std::invalid_argument);
	EXPECT_THROW(HocGeometry({-1.0}, 0), std::invalid_argument);
	EXPECT_THROW(HocGeometry({1.0}, 4), std::invalid_argument);
}

TEST(HocHistogram, IncrementsDecrementsClampAndSigmoidWeights)
{
	HocOptions o;
	o.sigmoidGain = 0.7;
	o.sigmoidOffset = 1.5;
	HocHistogram h;
	EXPECT_FALSE(h.touched());
	EXPECT_EQ(h.count(5), 0);
	EXPECT_EQ(h.maxCount(), 0);
	h.add(5, +1, 3, 60);
	h.add(5, +1, 3, 60);
	h.add(7, -1, 3, 60);
	EXPECT_EQ(h.count(5), 2);
	EXPECT_EQ(h.count(7), -1);
	EXPECT_EQ(h.count(6), 0);
	EXPECT_EQ(h.maxCount(), 2);
	for (int i = 0; i < 10; i++) h.add(5, +1, 3, 60), h.add(7, -1, 3, 60);
	EXPECT_EQ(h.count(5), 3);
	EXPECT_EQ(h.count(7), -3);
	EXPECT_THROW(h.add(60, 1, 3, 60), std::out_of_range);
	for (int n = -5; n <= 5; n++) EXPECT_NEAR(o.weight(n), 1.0 / (1.0 + std::exp(-0.7 * (n - 1.5))), 1e-15);
	EXPECT_DOUBLE_EQ(HocOptions().weight(0), 0.5);
}

TEST(HocOptions, IniRoundTripAndErrorsNameTheKey)
{
	mrpt::config::CConfigFileMemory c;
	c.setContent(std::string("[hoc]\nenabled = true\nradii = 0.5 2 5\nsubdivisions = 1\nprune_threshold = 0.7\ncount_limit = 9\n"));
	HocOptions o;
	o.loadFromConfigFile(c, "hoc");
	EXPECT_TRUE(o.enabled);
	EXPECT_EQ(o.radii, (std::vector<double>{0.5, 2, 5}));
	EXPECT_EQ(o.subdivisions, 1);
	EXPECT_DOUBLE_EQ(o.pruneThreshold, 0.7);
	EXPECT_EQ(o.countLimit, 9);
	for (const char* bad : {"radii = 2 1", "radii = 1 x", "subdivisions = 1.5", "prune_threshold = 2", "count_limit = 0", "initial_count = 0", "sigmoid_gain = -1", "enabled = maybe"})
	{
		mrpt::config::CConfigFileMemory b;
		b.setContent(std::string("[hoc]\n") + bad + "\n");
		const std::string key = std::string(bad).substr(0, std::string(bad).find(' '));
		try
		{
			HocOptions x;
			x.loadFromConfigFile(b, "hoc");
			ADD_FAILURE() << "accepted: " << bad;
		}
		catch (const std::invalid_argument& e)
		{
			EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
		}
	}
}
