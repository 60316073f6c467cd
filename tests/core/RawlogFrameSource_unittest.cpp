#include <keygrid/core/DepthRegistration.h>
#include <keygrid/core/FrameConventions.h>
#include <keygrid/core/RawlogFrameSource.h>
#include <keygrid/core/RawlogWriter.h>
#include <keygrid/core/RgbdObservation.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/system/filesystem.h>
#include <opencv2/core.hpp>

#include "TestData.h"

#include <cstdio>
#include <fstream>

using namespace keygrid::core;

TEST(RawlogFrameSource, RealKinectFrameFromMrptDatasets)
{
	const std::string path = keygrid::test::mrptDatasetsDir() + "/tests_rgbd.rawlog";
	if (!mrpt::system::fileExists(path)) GTEST_SKIP() << path << " missing (package mrpt-common)";
	RawlogFrameSource src(path);
	Frame f;
	ASSERT_TRUE(src.next(f));
	EXPECT_EQ(f.grey.size(), cv::Size(640, 480));
	EXPECT_EQ(f.colour.type(), CV_8UC3);
	EXPECT_FLOAT_EQ(f.camera.depthUnits, 0.001f);
	// The frame lives in the colour camera (depth registered into it).
	EXPECT_NEAR(f.camera.fx, 521.179233, 1e-6);
	int valid = 0;
	for (int r = 0; r < 480; r++)
		for (int c = 0; c < 640; c++) valid += f.depth.at<float>(r, c) > 0;
	EXPECT_GT(valid, 640 * 480 / 2);
	EXPECT_FALSE(src.next(f));
}

TEST(RawlogFrameSource, RegistrationMatchesAnalyticPlaneDepth)
{
	// Depth camera sees a tilted plane; the colour camera sits 2.5 cm to its right with other
	// intrinsics. Registered depth must equal the plane's analytic depth in the colour camera.
	mrpt::img::TCamera dc, ic;
	dc.ncols = ic.ncols = 160;
	dc.nrows = ic.nrows = 120;
	dc.setIntrinsicParamsFromValues(150, 150, 80, 60);
	ic.setIntrinsicParamsFromValues(140, 141, 79, 61);
	// Plane in the depth camera's optical frame: n.p = c, n = (0.1, 0.2, 1)/|.|, c = 2 m.
	const Eigen::Vector3d n = Eigen::Vector3d(0.1, 0.2, 1.0).normalized();
	const double c0 = 2.0;
	const float units = 0.0002f;
	cv::Mat raw(120, 160, CV_16UC1);
	for (int r = 0; r < 120; r++)
		for (int c = 0; c < 160; c++)
		{
			const Eigen::Vector3d ray((c - 80) / 150.0, (r - 60) / 150.0, 1.0);
			raw.at<uint16_t>(r, c) = static_cast<uint16_t>(std::lround(c0 / n.dot(ray) / units));
		}
	// T_depthCam_int: intensity optical frame 2.5 cm along the depth camera's optical +x.
	const mrpt::poses::CPose3D T_depthCam_int(0.025, 0, 0, 0, 0, 0);
	const mrpt::poses::CPose3D T_depth_int = T_depth_cam() + T_depthCam_int;
	const cv::Mat reg = registerDepthToIntensity(raw, units, dc, ic, T_depth_int);
	// In the intensity frame the plane is n.(p + t) = c  ->  n.p = c - n.t
	const double c1 = c0 - n.dot(Eigen::Vector3d(0.025, 0, 0));
	int checked = 0;
	for (int r = 10; r < 110; r++)
		for (int c = 10; c < 150; c++)
		{
			const uint16_t v = reg.at<uint16_t>(r, c);
			if (!v) continue;
			const Eigen::Vector3d ray((c - 79) / 140.0, (r - 61) / 141.0, 1.0);
			const double expect = c1 / n.dot(ray);
			// nearest-pixel splatting: half a pixel of slope plus quantisation
			ASSERT_NEAR(v * units, expect, 3e-3) << r << "," << c;
			++checked;
		}
	EXPECT_GT(checked, 100 * 140 * 0.8);
}

TEST(RawlogFrameSource, SkipsNonRgbdAndReportsTruncation)
{
	const std::string dir = keygrid::test::scratchDir("rawlog_source");
	Frame f;
	f.camera.width = 8;
	f.camera.height = 6;
	f.grey = cv::Mat(6, 8, CV_8UC1, cv::Scalar(7));
	f.depthRaw = cv::Mat(6, 8, CV_16UC1, cv::Scalar(5000));
	{
		RawlogWriter w(dir + "/mixed.rawlog");
		w.write(mrpt::obs::CObservation2DRangeScan::Create());  // not RGB-D: counted skip
		w.write(makeRgbdObservation(f));
		auto noImage = makeRgbdObservation(f);
		noImage->hasIntensityImage = false;
		w.write(noImage);  // counted skip
		w.write(makeRgbdObservation(f));
		w.close();
	}
	{
		RawlogFrameSource src(dir + "/mixed.rawlog");
		Frame g;
		int n = 0;
		while (src.next(g)) ++n;
		EXPECT_EQ(n, 2);
		EXPECT_EQ(src.skippedCount(), 2u);
		EXPECT_NE(src.lastSkipReason().find("no intensity image"), std::string::npos);
	}
	// Truncate the file in the middle of the second observation.
	{
		std::ifstream in(dir + "/mixed.rawlog", std::ios::binary);
		std::string bytes((std::istreambuf_iterator<char>(in)), {});
		std::ofstream(dir + "/cut.rawlog", std::ios::binary) << bytes.substr(0, bytes.size() * 2 / 3);
	}
	RawlogFrameSource cut(dir + "/cut.rawlog");
	Frame g;
	bool threw = false;
	int n = 0;
	try
	{
		while (cut.next(g)) ++n;
	}
	catch (const std::runtime_error& e)
	{
		threw = true;
		EXPECT_NE(std::string(e.what()).find("cut.rawlog"), std::string::npos) << e.what();
	}
	EXPECT_TRUE(threw || n < 2) << "a truncated rawlog must not yield every frame silently";
	EXPECT_THROW(RawlogFrameSource("/nonexistent.rawlog"), std::runtime_error);
	EXPECT_THROW(openFrameSource("/nonexistent/path"), std::runtime_error);
}

TEST(RawlogFrameSource, DepthIgnoredGivesTheImagesOfTheRgbdFrames)
{
	// A real (unregistered) Kinect frame: the image-only frame is the RGB-D frame's grey and
	// colour image in the same camera, without depth.
	const std::string path = keygrid::test::mrptDatasetsDir() + "/tests_rgbd.rawlog";
	if (!mrpt::system::fileExists(path)) GTEST_SKIP() << path << " missing (package mrpt-common)";
	Frame rgbd, mono;
	RawlogFrameSource withDepth(path);
	ASSERT_TRUE(withDepth.next(rgbd));
	ASSERT_TRUE(rgbd.hasDepth());
	FrameSourceOptions so;
	so.depth = DepthUse::Ignore;
	RawlogFrameSource imagesOnly(path, so);
	ASSERT_TRUE(imagesOnly.next(mono));
	EXPECT_FALSE(mono.hasDepth());
	EXPECT_TRUE(mono.depthRaw.empty());
	EXPECT_EQ(cv::norm(mono.grey, rgbd.grey, cv::NORM_INF), 0.0);
	EXPECT_EQ(cv::norm(mono.colour, rgbd.colour, cv::NORM_INF), 0.0);
	EXPECT_EQ(mono.timestamp, rgbd.timestamp);
	EXPECT_EQ(mono.camera.fx, rgbd.camera.fx);
	EXPECT_EQ(mono.camera.cy, rgbd.camera.cy);
	EXPECT_EQ(mono.camera.dist, rgbd.camera.dist);
	EXPECT_FALSE(imagesOnly.next(mono));
	EXPECT_EQ(imagesOnly.skippedCount(), 0u);
}

TEST(RawlogFrameSource, DepthIgnoredLoadsNoDepth)
{
	// Range images stored in external files that are gone: RGB-D mode cannot load them and skips
	// the entries; with depth ignored they are never opened, and entries without any range
	// image are frames too.
	const std::string dir = keygrid::test::scratchDir("rawlog_nodepth");
	// A 12 x 9 frame: a grey ramp, depth 1 m.
	Frame f;
	f.camera.width = 12;
	f.camera.height = 9;
	f.grey.create(9, 12, CV_8UC1);
	for (int r = 0; r < 9; r++)
		for (int c = 0; c < 12; c++) f.grey.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(20 * r + c);
	f.depthRaw = cv::Mat(9, 12, CV_16UC1, cv::Scalar(5000));
	const std::string imagesDir = dir + "/ext_Images";
	mrpt::system::createDirectory(imagesDir);
	{
		RawlogWriter w(dir + "/ext.rawlog");
		auto noRange = makeRgbdObservation(f);
		noRange->hasRangeImage = false;
		noRange->rangeImage.setSize(0, 0);
		w.write(noRange);
		auto external = makeRgbdObservation(f);
		external->rangeImage_convertToExternalStorage("range_0.bin", imagesDir + "/");
		w.write(external);
		w.close();
	}
	ASSERT_TRUE(mrpt::system::fileExists(imagesDir + "/range_0.bin"));
	{
		// While the file exists, RGB-D mode reads its depth: the setup stores depth externally.
		RawlogFrameSource src(dir + "/ext.rawlog");
		Frame g;
		ASSERT_TRUE(src.next(g)) << src.lastSkipReason();
		EXPECT_EQ(g.depthRaw.at<uint16_t>(3, 4), 5000);
	}
	std::remove((imagesDir + "/range_0.bin").c_str());
	{
		RawlogFrameSource src(dir + "/ext.rawlog");
		Frame g;
		EXPECT_FALSE(src.next(g));
		EXPECT_EQ(src.skippedCount(), 2u);
		EXPECT_NE(src.lastSkipReason().find("rawlog entry 1: cannot load external image"), std::string::npos)
			<< src.lastSkipReason();
	}
	FrameSourceOptions so;
	so.depth = DepthUse::Ignore;
	RawlogFrameSource src(dir + "/ext.rawlog", so);
	Frame g;
	for (int i = 0; i < 2; i++)
	{
		ASSERT_TRUE(src.next(g)) << src.lastSkipReason();
		EXPECT_FALSE(g.hasDepth());
		EXPECT_EQ(cv::norm(g.grey, f.grey, cv::NORM_INF), 0.0);
	}
	EXPECT_FALSE(src.next(g));
	EXPECT_EQ(src.skippedCount(), 0u);
}

TEST(RawlogFrameSource, DepthIgnoredSkipsOtherSensorsNamingThem)
{
	const std::string dir = keygrid::test::scratchDir("rawlog_nodepth_other");
	{
		RawlogWriter w(dir + "/laser.rawlog");
		w.write(mrpt::obs::CObservation2DRangeScan::Create());
		w.close();
	}
	FrameSourceOptions so;
	so.depth = DepthUse::Ignore;
	RawlogFrameSource src(dir + "/laser.rawlog", so);
	Frame g;
	EXPECT_FALSE(src.next(g));
	EXPECT_EQ(src.skippedCount(), 1u);
	EXPECT_NE(src.lastSkipReason().find("CObservation2DRangeScan is not an image observation"), std::string::npos)
		<< src.lastSkipReason();
}
