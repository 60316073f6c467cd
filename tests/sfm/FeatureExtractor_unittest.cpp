#include <keygrid/sfm/FeatureExtractor.h>

#include <algorithm>
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
