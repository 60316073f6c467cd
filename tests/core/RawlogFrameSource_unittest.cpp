#include <keygrid/core/DepthRegistration.h>
#include <keygrid/core/FrameConventions.h>
#include <keygrid/core/RawlogFrameSource.h>
#include <keygrid/core/RawlogWriter.h>
#include <keygrid/core/RgbdObservation.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/system/filesystem.h>

#include "TestData.h"

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
