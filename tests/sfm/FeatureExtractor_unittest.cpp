#include <keygrid/sfm/FeatureExtractor.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "TestData.h"

using namespace keygrid;

namespace
{
core::Frame texturedFrame(unsigned seed)
{
	core::Frame f;
	f.camera = core::RgbdCamera::Preset("fr1");
	cv::Mat img(480, 640, CV_8UC1, cv::Scalar(128));
	std::mt19937 g(seed);
	std::uniform_int_distribution<int> x(0, 639), y(0, 479), c(0, 255), s(3, 25);
	for (int i = 0; i < 700; i++)
		cv::rectangle(img, cv::Rect(x(g), y(g), s(g), s(g)), cv::Scalar(c(g)), cv::FILLED);
	f.grey = img;
	f.depth = cv::Mat(480, 640, CV_32FC1, cv::Scalar(2.0f));
	f.depth(cv::Rect(0, 0, 320, 480)) = 1.0f;  // a depth step at column 320
	f.depth(cv::Rect(600, 0, 40, 480)) = 0.0f;  // invalid strip
	return f;
}
}  // namespace

TEST(FeatureExtractor, BucketingSpreadsKeypointsAndKeepsTheBudget)
{
	std::vector<cv::KeyPoint> kps;
	for (int i = 0; i < 1000; i++) kps.emplace_back(cv::Point2f(10.f + (i % 50), 10.f + (i / 50)), 7.f, -1, 100.f + i);  // all in one corner
	for (int i = 0; i < 100; i++) kps.emplace_back(cv::Point2f(600.f, 10.f + 4 * i), 7.f, -1, 1.f);  // weak, elsewhere
	const auto out = sfm::bucketKeypoints(kps, {640, 480}, 8, 6, 200);
	ASSERT_EQ(out.size(), 200u);
	int elsewhere = 0;
	for (const auto& k : out) elsewhere += k.pt.x > 500;
	EXPECT_GE(elsewhere, 20) << "weak keypoints in empty cells must get their share";
}

TEST(FeatureExtractor, OrbFeaturesWithDepthValidity)
{
	sfm::FeatureOptions o;
	sfm::FeatureExtractor ex(o);
	const auto f = ex.extract(texturedFrame(1));
	EXPECT_GT(f.size(), 800u);
	EXPECT_LE(f.size(), 1000u);
	EXPECT_EQ(f.descriptors.rows, static_cast<int>(f.size()));
	EXPECT_EQ(f.descriptors.type(), CV_8U);
	int onEdge = 0, invalid = 0, ok = 0;
	for (std::size_t i = 0; i < f.size(); i++)
	{
		const float u = f.keypoints[i].pt.x, d = f.depth[i];
		const long c = std::lround(u);
		if (c == 319 || c == 320) onEdge += d > 0;  // their 3x3 windows straddle the step
		else if (c >= 599) invalid += d > 0;
		else if (d > 0)
		{
			++ok;
			EXPECT_FLOAT_EQ(d, u < 320 ? 1.0f : 2.0f);
		}
	}
	EXPECT_EQ(onEdge, 0) << "depth on a discontinuity must be rejected";
	EXPECT_EQ(invalid, 0);
	EXPECT_GT(ok, 600);
	// Undistortion moves points outward by the fr1 radial model (k1 > 0): corners move most.
	double maxShift = 0;
	for (std::size_t i = 0; i < f.size(); i++)
		maxShift = std::max(maxShift, cv::norm(f.undistorted[i] - f.keypoints[i].pt));
	EXPECT_GT(maxShift, 5.0);
	// Grid lookup agrees with brute force.
	const auto near = f.featuresInArea(300, 200, 25);
	int brute = 0;
	for (const auto& p : f.undistorted) brute += cv::norm(p - cv::Point2f(300, 200)) <= 25;
	EXPECT_EQ(static_cast<int>(near.size()), brute);
}

TEST(FeatureExtractor, AreaLookupsAgreeWithBruteForceAtEveryLevelRange)
{
	sfm::FeatureOptions o;
	sfm::FeatureExtractor ex(o);
	const auto f = ex.extract(texturedFrame(3));
	ASSERT_GT(f.size(), 500u);
	std::mt19937 g(7);
	std::uniform_real_distribution<float> u(-20.f, 660.f), v(-20.f, 500.f), r(0.5f, 30.f);
	std::vector<int> buffer{42, 43};  // stale content must be cleared
	int nonEmpty = 0, empty = 0;
	for (int q = 0; q < 400; q++)
	{
		const float cu = u(g), cv_ = v(g), rad = q % 4 == 0 ? 2.f : r(g);
		const int minLevel = q % 3 == 0 ? -1 : q % 5, maxLevel = q % 3 == 0 ? -1 : q % 5 + 1;
		std::vector<int> brute;
		for (std::size_t i = 0; i < f.size(); i++)
		{
			const int lvl = f.keypoints[i].octave;
			if (minLevel >= 0 && lvl < minLevel) continue;
			if (maxLevel >= 0 && lvl > maxLevel) continue;
			const float dx = f.undistorted[i].x - cu, dy = f.undistorted[i].y - cv_;
			if (dx * dx + dy * dy <= rad * rad) brute.push_back(static_cast<int>(i));
		}
		auto grid = f.featuresInArea(cu, cv_, rad, minLevel, maxLevel);
		f.featuresInArea(cu, cv_, rad, minLevel, maxLevel, buffer);
		EXPECT_EQ(grid, buffer);
		std::sort(grid.begin(), grid.end());
		EXPECT_EQ(grid, brute) << "query " << q;
		EXPECT_EQ(f.anyFeatureInArea(cu, cv_, rad, minLevel, maxLevel), !brute.empty()) << "query " << q;
		(brute.empty() ? empty : nonEmpty)++;
	}
	EXPECT_GT(empty, 20);  // both answers exercised
	EXPECT_GT(nonEmpty, 20);
}

TEST(FeatureExtractor, SiftIsSelectable)
{
	sfm::FeatureOptions o;
	o.type = "sift";
	o.numFeatures = 300;
	sfm::FeatureExtractor ex(o);
	const auto f = ex.extract(texturedFrame(2));
	EXPECT_GT(f.size(), 150u);
	EXPECT_EQ(f.descriptors.type(), CV_32F);
	EXPECT_EQ(f.descriptors.cols, 128);
	o.type = "surf";
	EXPECT_THROW(sfm::FeatureExtractor{o}, std::invalid_argument);
}

// OpenCV's ORB reports a keypoint found at integer pixel p_l of pyramid level l as p_l * 1.2^l.
// Level l is made from level l-1 by cv::resize to the rounded size, so resampling a ramp image
// I(u, v) = u (resp. v) the same way gives, at p_l, the level-0 position that pixel really sees:
// the independent reference for levelZeroPosition().
TEST(FeatureExtractor, PyramidKeypointsMapToLevelZeroThroughPixelCentres)
{
	sfm::FeatureOptions o;
	sfm::FeatureExtractor ex(o);
	const cv::Size size(640, 480);
	cv::Mat rampU(size, CV_32FC1), rampV(size, CV_32FC1);
	for (int r = 0; r < size.height; r++)
		for (int c = 0; c < size.width; c++) rampU.at<float>(r, c) = c, rampV.at<float>(r, c) = r;
	cv::Mat levelU = rampU, levelV = rampV;
	double maxOpenCvError = 0;
	for (int l = 1; l < o.numLevels; l++)
	{
		const float s = static_cast<float>(std::pow(o.scaleFactor, static_cast<double>(l)));
		const cv::Size sz(cvRound(size.width / s), cvRound(size.height / s));
		cv::resize(levelU, levelU, sz, 0, 0, cv::INTER_LINEAR);
		cv::resize(levelV, levelV, sz, 0, 0, cv::INTER_LINEAR);
		for (const cv::Point p : {cv::Point(3, 3), cv::Point(sz.width / 2, sz.height / 3), cv::Point(sz.width - 4, sz.height - 4)})
		{
			cv::KeyPoint kp(cv::Point2f(p.x * s, p.y * s), 31.f * s, -1, 1.f, l);
			const cv::Point2f u0 = ex.levelZeroPosition(kp, size);
			EXPECT_NEAR(u0.x, levelU.at<float>(p), 2e-3) << "level " << l << " pixel " << p;
			EXPECT_NEAR(u0.y, levelV.at<float>(p), 2e-3) << "level " << l << " pixel " << p;
			maxOpenCvError = std::max(maxOpenCvError, static_cast<double>(std::abs(kp.pt.x - levelU.at<float>(p))));
		}
	}
	EXPECT_GT(maxOpenCvError, 1.0) << "OpenCV's own u_l * s^l is off by > 1 px at the top levels";

	// The convention assumed above: detected keypoints sit at integer pixels of their level.
	o.pyramidPixelCentres = false;
	sfm::FeatureExtractor raw(o);
	const auto f = raw.extract(texturedFrame(3));
	int checked = 0;
	for (const auto& kp : f.keypoints)
	{
		if (kp.octave == 0) continue;
		const float s = static_cast<float>(std::pow(o.scaleFactor, static_cast<double>(kp.octave)));
		EXPECT_NEAR(kp.pt.x / s, std::round(kp.pt.x / s), 1e-3);
		EXPECT_NEAR(kp.pt.y / s, std::round(kp.pt.y / s), 1e-3);
		++checked;
	}
	EXPECT_GT(checked, 100);
	// With the option on, the same detections move by the mapping (level 0 stays put).
	o.pyramidPixelCentres = true;
	const auto g = sfm::FeatureExtractor(o).extract(texturedFrame(3));
	ASSERT_EQ(g.size(), f.size());
	for (std::size_t i = 0; i < f.size(); i++)
	{
		const cv::Point2f want = ex.levelZeroPosition(f.keypoints[i], size);
		EXPECT_NEAR(g.keypoints[i].pt.x, want.x, 1e-4);
		EXPECT_NEAR(g.undistorted[i].x - f.undistorted[i].x, 0.f, 2.f);
	}
}
