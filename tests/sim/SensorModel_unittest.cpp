// Depth of a known plane: exact with the noise off, Kinect sigma(z) with the noise on.
#include <keygrid/sim/SensorModel.h>
#include <keygrid/sim/SequenceWriter.h>
#include <keygrid/sim/Simulator.h>

#include <opencv2/core.hpp>

#include "SimTestScenes.h"
#include "TestData.h"

#include <cmath>

using namespace keygrid;

TEST(SensorModel, TiltedPlaneDepthIsExactWithNoiseOff)
{
	// The wall x = 3 seen by a camera at (0, 0, 1) yawed by 25 deg: in the optical frame the
	// plane is n.p = c with n = R_cam_world * (1, 0, 0), c = 3 (camera at x = 0).
	const std::string ini =
		"[scene]\nseed = 3\nframes = 1\n" + test::tinyCameraIni() +
		"[sensor]\nnoise = false\nmax_incidence_deg = 90\nmax_range = 10\n"
		"[trajectory]\nwp_00 = 0 0 1  5 2.3316 1\n"  // atan(2.3316 / 5) = 25 deg
		"[object.wall]\ntype = quad\ncorner = 3 -20 -20\nedge1 = 0 40 0\nedge2 = 0 0 40\n";
	const sim::Scene scene = test::sceneFromString(ini);
	const sim::Simulator simulator(scene, 1);
	sim::SimFrame f;
	simulator.frame(0, f);
	const Eigen::Isometry3d T_wc = sim::Renderer::toIsometry(f.T_world_cam);
	const Eigen::Vector3d n = T_wc.linear().transpose() * Eigen::Vector3d::UnitX();
	const double c = 3.0 - Eigen::Vector3d::UnitX().dot(T_wc.translation());
	int checked = 0;
	for (int v = 0; v < 120; v++)
		for (int u = 0; u < 160; u++)
		{
			const Eigen::Vector3d ray((u - 79.5) / 131.25, (v - 59.5) / 131.25, 1.0);
			const double z = c / n.dot(ray);
			ASSERT_NEAR(f.render.depth.at<float>(v, u), z, 2e-6 * z) << "pixel " << u << "," << v;
			// Stored depth: the nearest multiple of depthUnits (the 0.1 mm raw resolution).
			ASSERT_LE(std::abs(f.frame.depth.at<float>(v, u) - z), 0.0001 + 1e-6);
			checked++;
		}
	EXPECT_EQ(checked, 160 * 120);
	// No noise: the measured colour is the rendered colour.
	EXPECT_EQ(cv::norm(f.frame.colour, f.render.colour, cv::NORM_INF), 0.0);
}

TEST(SensorModel, PlaneDepthNoiseHasTheKinectSigma)
{
	for (double wallX : {1.0, 2.5, 4.0})
	{
		// Frontal wall: every pixel of a frame sees depth z = wallX exactly, so the sample
		// standard deviation of the measured depth estimates sigma(z) directly.
		const sim::Scene scene = test::sceneFromString(test::wallSceneIni(
			wallX,
			"noise = true\nquantise_disparity = false\ndropout_probability = 0\nmax_incidence_deg "
			"= 90\nmax_range = 6"));
		const sim::Simulator simulator(scene, 2);
		double sum = 0, sum2 = 0;
		std::size_t n = 0;
		sim::SimFrame f;
		for (std::size_t i = 0; i < 3; i++)
		{
			simulator.frame(i, f);
			for (int v = 0; v < 120; v++)
				for (int u = 0; u < 160; u++)
				{
					const double e = f.frame.depth.at<float>(v, u) - wallX;
					sum += e;
					sum2 += e * e;
					n++;
				}
		}
		const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
		const double sigma = 0.0012 + 0.0019 * (wallX - 0.4) * (wallX - 0.4);
		// The 0.2 mm storage step adds (0.0002)^2 / 12 to the variance.
		const double expected = std::sqrt(sigma * sigma + 0.0002 * 0.0002 / 12.0);
		// n = 57600: the relative standard error of a Gaussian sample sd is 1/sqrt(2n) = 0.3 %;
		// 2 % is ~7 standard errors. The mean is within 5 sigma/sqrt(n) of zero.
		EXPECT_NEAR(sd, expected, 0.02 * expected) << "z = " << wallX;
		EXPECT_NEAR(mean, 0.0, 5 * sigma / std::sqrt(static_cast<double>(n))) << "z = " << wallX;
	}
}

TEST(SensorModel, DisparityQuantisationRangeAndGrazingLimits)
{
	sim::SensorOptions o;
	o.sigmaA = o.sigmaB = 0;  // quantisation only
	o.dropoutProbability = 0;
	o.imageNoiseSigma = 0;
	o.minRange = 0.5;
	o.maxRange = 4.0;
	o.maxIncidenceDeg = 70;
	const double f = 525, fB = f * o.baseline;
	const sim::SensorModel model(o, f, 7, 1);
	cv::Mat z(1, 6, CV_32FC1), cosI(1, 6, CV_32FC1, cv::Scalar(1.0f)), out;
	cv::Mat colour(1, 6, CV_8UC3, cv::Scalar(0, 0, 0));
	const float zs[6] = {0.3f, 1.0f, 2.2345f, 3.9f, 4.5f, 2.0f};
	for (int i = 0; i < 6; i++) z.at<float>(0, i) = zs[i];
	cosI.at<float>(0, 5) = static_cast<float>(std::cos(75 * M_PI / 180));  // too grazing
	model.apply(0, z, cosI, out, colour);
	EXPECT_EQ(out.at<float>(0, 0), 0.0f);  // nearer than min_range
	EXPECT_EQ(out.at<float>(0, 4), 0.0f);  // beyond max_range
	EXPECT_EQ(out.at<float>(0, 5), 0.0f);  // incidence 75 deg > 70 deg
	for (int i = 1; i <= 3; i++)
	{
		const double zq = out.at<float>(0, i);
		// Disparity 8 fB / z is an integer number of 1/8-pixel steps, and the nearest one.
		const double steps = 8 * fB / zq;
		EXPECT_NEAR(steps, std::round(steps), 1e-3) << zq;
		EXPECT_EQ(std::round(steps), std::round(8 * fB / zs[i]));
		// Half a step in depth: z^2 / (2 * 8 fB).
		EXPECT_LE(std::abs(zq - zs[i]), zs[i] * zs[i] / (16 * fB) + 1e-6);
	}
}

TEST(SensorModel, DisparityDistortionFollowsTheRadialClosedForm)
{
	// Noise off, k = 0.4 px: z' = f B / (f B / z - k rho^2) with rho^2 = r^2 / r_corner^2 from
	// the image centre. Centre pixel of an odd-sized image unchanged, corners the largest
	// error, and a pixel halfway along the diagonal gets rho^2 = 1/4.
	sim::SensorOptions o;
	o.noise = false;
	o.maxIncidenceDeg = 90;
	o.maxRange = 20;
	o.disparityDistortion = 0.4;
	const double f = 525, fB = f * o.baseline;
	const sim::SensorModel model(o, f, 7, 1);
	const int W = 81, H = 61;
	const double cx = 40, cy = 30, z = 3.0;
	cv::Mat depth(H, W, CV_32FC1, cv::Scalar(z)), cosI(H, W, CV_32FC1, cv::Scalar(1.0f)), out;
	cv::Mat colour(H, W, CV_8UC3, cv::Scalar(0, 0, 0));
	model.apply(0, depth, cosI, out, colour);
	const auto expected = [&](int u, int v) {
		const double rho2 = ((u - cx) * (u - cx) + (v - cy) * (v - cy)) / (cx * cx + cy * cy);
		return fB / (fB / z - 0.4 * rho2);
	};
	EXPECT_FLOAT_EQ(out.at<float>(30, 40), static_cast<float>(z));
	EXPECT_NEAR(out.at<float>(0, 0), fB / (fB / z - 0.4), 1e-5);
	EXPECT_NEAR(out.at<float>(H - 1, W - 1), fB / (fB / z - 0.4), 1e-5);
	EXPECT_NEAR(out.at<float>(15, 20), fB / (fB / z - 0.1), 1e-5);  // rho^2 = 1/4
	// 3 m at the corner: 3 * 0.4 * 3 / 39.375 = 3.1 % deeper.
	EXPECT_NEAR(out.at<float>(0, 0) / z - 1, 0.4 * z / fB, 0.002);
	for (int v = 0; v < H; v += 7)
		for (int u = 0; u < W; u += 5) ASSERT_NEAR(out.at<float>(v, u), expected(u, v), 1e-5);
	// A disparity offset larger than the disparity itself leaves no valid depth.
	o.disparityDistortion = 20;  // > f B / 3 m = 13.1 px at the corners
	const sim::SensorModel strong(o, f, 7, 1);
	strong.apply(0, depth, cosI, out, colour);
	EXPECT_EQ(out.at<float>(0, 0), 0.0f);
	EXPECT_FLOAT_EQ(out.at<float>(30, 40), static_cast<float>(z));
}

TEST(SensorModel, OptionsRejectBadValuesNamingTheKey)
{
	const std::string ini = test::wallSceneIni(2.0, "max_range = -1");
	try
	{
		test::sceneFromString(ini);
		FAIL() << "max_range = -1 accepted";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("max_range"), std::string::npos) << e.what();
	}
	EXPECT_THROW(
		test::sceneFromString(test::wallSceneIni(2.0, "min_range = 3\nmax_range = 2")),
		std::invalid_argument);
	EXPECT_THROW(
		test::sceneFromString(test::wallSceneIni(2.0, "nosie = true")), std::invalid_argument);
}

TEST(SensorModel, OptionStructsRoundTripThroughIni)
{
	sim::SensorOptions s;
	s.noise = false;
	s.sigmaA = 0.002;
	s.maxRange = 3.5;
	s.maxIncidenceDeg = 70;
	s.dropoutProbability = 0.01;
	s.disparityDistortion = 0.15;
	sim::OutputOptions o;
	o.writeMask = true;
	o.voxelResolution = 0.1;
	o.floorPlanZMax = 2.0;
	o.pngCompression = 3;
	sim::SceneOptions sc;
	sc.name = "rt";
	sc.seed = 12345678901ULL;
	sc.frames = 77;
	sc.startTime = 1234.5;
	mrpt::config::CConfigFileMemory cfg;
	s.saveToConfigFile(cfg, "sensor");
	o.saveToConfigFile(cfg, "output");
	sc.saveToConfigFile(cfg, "scene");
	sim::SensorOptions s2;
	sim::OutputOptions o2;
	sim::SceneOptions sc2;
	s2.loadFromConfigFile(cfg, "sensor");
	o2.loadFromConfigFile(cfg, "output");
	sc2.loadFromConfigFile(cfg, "scene");
	EXPECT_EQ(s2.noise, false);
	EXPECT_DOUBLE_EQ(s2.sigmaA, 0.002);
	EXPECT_DOUBLE_EQ(s2.maxRange, 3.5);
	EXPECT_DOUBLE_EQ(s2.maxIncidenceDeg, 70);
	EXPECT_DOUBLE_EQ(s2.dropoutProbability, 0.01);
	EXPECT_DOUBLE_EQ(s2.disparityDistortion, 0.15);
	EXPECT_TRUE(o2.writeMask);
	EXPECT_DOUBLE_EQ(o2.voxelResolution, 0.1);
	EXPECT_DOUBLE_EQ(o2.floorPlanZMax, 2.0);
	EXPECT_EQ(o2.pngCompression, 3);
	EXPECT_EQ(sc2.name, "rt");
	EXPECT_EQ(sc2.seed, 12345678901ULL);
	EXPECT_EQ(sc2.frames, 77u);
	EXPECT_DOUBLE_EQ(sc2.startTime, 1234.5);
}
