// Monocular input from rawlogs: CObservationImage entries (as rawlog-grabber records a USB
// camera) read back as image-only frames with their timestamps and intrinsics, and the shipped
// rawlog-grabber INI for a USB camera.
#include <keygrid/core/ImageObservation.h>
#include <keygrid/core/RawlogFrameSource.h>
#include <keygrid/core/RawlogWriter.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "TestChecks.h"
#include "TestData.h"

#include <algorithm>

using namespace keygrid::core;
using keygrid::test::sameBits;

namespace
{
cv::Mat randomImage(int w, int h, int type, unsigned seed)
{
	cv::Mat m(h, w, type);
	cv::RNG rng(seed);
	rng.fill(m, cv::RNG::UNIFORM, 0, 256);
	return m;
}

/** What rawlog-grabber's CCameraSensor records for an OpenCV camera: image, timestamp, label,
 * and MRPT's default calibration (fx = fy = 0). */
mrpt::obs::CObservationImage::Ptr uncalibratedObservation(const cv::Mat& img, double t)
{
	auto obs = mrpt::obs::CObservationImage::Create();
	obs->sensorLabel = "CAMERA";
	obs->timestamp = mrpt::Clock::fromDouble(t);
	obs->image = mrpt::img::CImage(img, mrpt::img::DEEP_COPY);
	return obs;
}

std::size_t countFrames(FrameSource& src)
{
	Frame f;
	std::size_t n = 0;
	while (src.next(f)) n++;
	return n;
}
}  // namespace

TEST(ImageObservation, RawlogOfImageObservationsReadsBackImagesTimestampsAndIntrinsics)
{
	// Written with MRPT's own API: two plain observations (colour, grey) and one inside a
	// sensory frame (the rawlog format of use_sensoryframes = 1).
	const std::string path = keygrid::test::scratchDir("image_obs_rawlog") + "/mono.rawlog";
	const std::vector<cv::Mat> images = {
		randomImage(32, 24, CV_8UC3, 1), randomImage(32, 24, CV_8UC1, 2), randomImage(32, 24, CV_8UC3, 3)};
	const std::vector<double> stamps = {1700000000.0, 1700000000.0333, 1700000000.0667};
	mrpt::img::TCamera K;
	K.ncols = 32;
	K.nrows = 24;
	K.setIntrinsicParamsFromValues(40.5, 41.25, 15.75, 11.5);
	K.setDistortionPlumbBob(0.1, -0.05, 0.001, -0.002, 0.01);
	{
		mrpt::io::CFileGZOutputStream out(path);
		auto arch = mrpt::serialization::archiveFrom(out);
		for (std::size_t i = 0; i < images.size(); i++)
		{
			auto obs = uncalibratedObservation(images[i], stamps[i]);
			obs->cameraParams = K;
			if (i < 2)
				arch << *obs;
			else
			{
				mrpt::obs::CSensoryFrame sf;
				sf.insert(obs);
				arch << sf;
			}
		}
	}
	FrameSourceOptions mono;
	mono.depth = DepthUse::Ignore;
	RawlogFrameSource src(path, mono);
	Frame f;
	for (std::size_t i = 0; i < images.size(); i++)
	{
		ASSERT_TRUE(src.next(f)) << "frame " << i;
		EXPECT_EQ(f.index, i);
		EXPECT_FALSE(f.hasDepth());
		EXPECT_TRUE(f.depthRaw.empty());
		EXPECT_NEAR(f.timestamp, stamps[i], 1e-6);  // MRPT stores 100 ns ticks
		if (images[i].channels() == 3)
		{
			EXPECT_TRUE(sameBits(f.colour, images[i])) << "frame " << i;
			cv::Mat grey;
			cv::cvtColor(images[i], grey, cv::COLOR_BGR2GRAY);
			EXPECT_TRUE(sameBits(f.grey, grey)) << "frame " << i;
		}
		else
		{
			EXPECT_TRUE(f.colour.empty());
			EXPECT_TRUE(sameBits(f.grey, images[i]));
		}
		EXPECT_EQ(f.camera.width, 32u);
		EXPECT_EQ(f.camera.height, 24u);
		EXPECT_DOUBLE_EQ(f.camera.fx, 40.5);
		EXPECT_DOUBLE_EQ(f.camera.fy, 41.25);
		EXPECT_DOUBLE_EQ(f.camera.cx, 15.75);
		EXPECT_DOUBLE_EQ(f.camera.cy, 11.5);
		EXPECT_DOUBLE_EQ(f.camera.dist[0], 0.1);
		EXPECT_DOUBLE_EQ(f.camera.dist[3], -0.002);
		EXPECT_DOUBLE_EQ(f.camera.dist[4], 0.01);
	}
	EXPECT_FALSE(src.next(f));
	EXPECT_EQ(src.skippedCount(), 0u);
	EXPECT_NE(src.describe().find("depth ignored"), std::string::npos) << src.describe();

	// RGB-D mode: image observations are not frames; they are skipped and counted, as before.
	RawlogFrameSource rgbd(path);
	EXPECT_EQ(countFrames(rgbd), 0u);
	EXPECT_EQ(rgbd.skippedCount(), 3u);
	EXPECT_NE(rgbd.lastSkipReason().find("CObservationImage is not an RGB-D observation"), std::string::npos)
		<< rgbd.lastSkipReason();
}

TEST(ImageObservation, WriterRoundTripWithExternalImagesIsBitExact)
{
	const std::string dir = keygrid::test::scratchDir("image_obs_writer");
	Frame in;
	in.timestamp = 1234.5;
	in.colour = randomImage(20, 10, CV_8UC3, 7);
	cv::cvtColor(in.colour, in.grey, cv::COLOR_BGR2GRAY);
	in.camera = RgbdCamera::Preset("fr1");
	in.camera.width = 20;
	in.camera.height = 10;
	in.depth = cv::Mat(10, 20, CV_32FC1, cv::Scalar(1.5f));  // not stored in an image observation
	{
		RawlogWriterOptions wo;
		wo.externalImages = true;
		RawlogWriter w(dir + "/ext.rawlog", wo);
		w.write(makeImageObservation(in));
		w.close();
	}
	EXPECT_TRUE(mrpt::system::fileExists(dir + "/ext_Images/rgb_000000.png"));
	FrameSourceOptions mono;
	mono.depth = DepthUse::Ignore;
	RawlogFrameSource src(dir + "/ext.rawlog", mono);
	Frame out;
	out.depth = cv::Mat(10, 20, CV_32FC1, cv::Scalar(2.0f));  // a reused frame keeps no stale depth
	ASSERT_TRUE(src.next(out));
	EXPECT_TRUE(sameBits(out.colour, in.colour));
	EXPECT_TRUE(sameBits(out.grey, in.grey));
	EXPECT_FALSE(out.hasDepth());
	EXPECT_NEAR(out.timestamp, 1234.5, 1e-6);
	EXPECT_DOUBLE_EQ(out.camera.fx, in.camera.fx);
	EXPECT_DOUBLE_EQ(out.camera.dist[4], in.camera.dist[4]);
	EXPECT_EQ(out.camera.name, "fr1");

	Frame empty;
	EXPECT_THROW(makeImageObservation(empty), std::invalid_argument);
}

TEST(ImageObservation, UncalibratedObservationsNeedAGivenCameraOfTheirSize)
{
	const std::string path = keygrid::test::scratchDir("image_obs_uncalibrated") + "/usb.rawlog";
	{
		RawlogWriter w(path);
		for (int i = 0; i < 2; i++) w.write(uncalibratedObservation(randomImage(16, 12, CV_8UC3, 9 + i), 10.0 + i));
		w.close();
	}
	FrameSourceOptions mono;
	mono.depth = DepthUse::Ignore;
	{
		RawlogFrameSource src(path, mono);
		EXPECT_EQ(countFrames(src), 0u);
		EXPECT_EQ(src.skippedCount(), 2u);
		EXPECT_NE(src.lastSkipReason().find("'CAMERA' has no calibration"), std::string::npos) << src.lastSkipReason();
		EXPECT_NE(src.lastSkipReason().find("rawlog entry 1"), std::string::npos) << src.lastSkipReason();
	}
	mono.camera = RgbdCamera::Preset("kinect");  // 640x480: not these images
	{
		RawlogFrameSource src(path, mono);
		EXPECT_EQ(countFrames(src), 0u);
		EXPECT_NE(src.lastSkipReason().find("the given camera is for 640x480 but the image is 16x12"), std::string::npos)
			<< src.lastSkipReason();
	}
	mono.camera->width = 16;
	mono.camera->height = 12;
	RawlogFrameSource src(path, mono);
	Frame f;
	ASSERT_TRUE(src.next(f));
	EXPECT_DOUBLE_EQ(f.camera.fx, 525.0);
	EXPECT_NEAR(f.timestamp, 10.0, 1e-6);
	ASSERT_TRUE(src.next(f));
	EXPECT_NEAR(f.timestamp, 11.0, 1e-6);
	EXPECT_EQ(src.skippedCount(), 0u);
}

TEST(ImageObservation, UsbCameraGrabberIniHasWhatCCameraSensorReads)
{
	const std::string path = keygrid::test::sourceDir() + "/config/rawlog-grabber/usb_camera.ini";
	ASSERT_TRUE(mrpt::system::fileExists(path));
	mrpt::config::CConfigFile ini(path);
	// rawlog-grabber's own keys.
	EXPECT_EQ(ini.read_string("global", "rawlog_prefix", ""), "./usb_camera");
	EXPECT_EQ(ini.read_int("global", "use_sensoryframes", -1), 0);
	EXPECT_GT(ini.read_int("global", "time_between_launches", 0), 0);
	// MRPT keeps whatever follows a value on its line: no trailing comments anywhere.
	std::vector<std::string> sections, sensors;
	ini.getAllSections(sections);
	for (const auto& s : sections)
	{
		std::vector<std::string> keys;
		ini.getAllKeys(s, keys);
		for (const auto& k : keys)
		{
			const std::string v = ini.read_string(s, k, "");
			EXPECT_EQ(v.find_first_of(";#"), std::string::npos) << "[" << s << "] " << k << " = " << v;
			EXPECT_EQ(v.find("//"), std::string::npos) << "[" << s << "] " << k << " = " << v;
		}
		if (s != "global" && !ini.read_bool(s, "rawlog-grabber-ignore", false)) sensors.push_back(s);
	}
	// Exactly one sensor thread: CCameraSensor through OpenCV, with the keys its
	// loadConfig_sensorSpecific reads for that grabber, in the ranges it accepts.
	ASSERT_EQ(sensors.size(), 1u);
	const std::string cam = sensors[0];
	EXPECT_EQ(ini.read_string(cam, "driver", ""), "CCameraSensor");
	EXPECT_EQ(ini.read_string(cam, "grabber_type", ""), "opencv");
	const std::vector<std::string> cvTypes = {
		"CAMERA_CV_AUTODETECT", "CAMERA_CV_DC1394", "CAMERA_CV_VFL", "CAMERA_CV_VFW", "CAMERA_CV_MIL"};
	EXPECT_NE(
		std::find(cvTypes.begin(), cvTypes.end(), ini.read_string(cam, "cv_camera_type", "")), cvTypes.end());
	EXPECT_GE(ini.read_int(cam, "cv_camera_index", -1), 0);
	EXPECT_GT(ini.read_double(cam, "process_rate", 0), 0);
	EXPECT_FALSE(ini.read_string(cam, "sensorLabel", "").empty());
	EXPECT_EQ(ini.read_string(cam, "external_images_format", ""), "png");
	for (const char* k : {"pose_x", "pose_y", "pose_z", "pose_yaw", "pose_pitch", "pose_roll"})
		EXPECT_TRUE(ini.keyExists(cam, k)) << k;

	// Its [camera] section is the calibration keygrid uses for the recording: valid, and of the
	// capture size.
	const RgbdCamera K = RgbdCamera::FromPresetOrFile(path);
	std::string err;
	EXPECT_TRUE(K.isValid(&err)) << err;
	EXPECT_EQ(K.name, "usb_camera");
	EXPECT_EQ(static_cast<int>(K.width), ini.read_int(cam, "cv_frame_width", 0));
	EXPECT_EQ(static_cast<int>(K.height), ini.read_int(cam, "cv_frame_height", 0));

	// A recording as this INI makes it (uncalibrated observations of the capture size, with the
	// INI's label) reads with that camera.
	const std::string rawlog = keygrid::test::scratchDir("usb_camera_ini") + "/usb.rawlog";
	{
		RawlogWriter w(rawlog);
		auto obs = uncalibratedObservation(randomImage(static_cast<int>(K.width), static_cast<int>(K.height), CV_8UC3, 4), 5.0);
		obs->sensorLabel = ini.read_string(cam, "sensorLabel", "");
		w.write(obs);
		w.close();
	}
	FrameSourceOptions mono;
	mono.depth = DepthUse::Ignore;
	mono.camera = K;
	auto src = openFrameSource(rawlog, mono);
	Frame f;
	ASSERT_TRUE(src->next(f)) << src->lastSkipReason();
	EXPECT_DOUBLE_EQ(f.camera.fx, K.fx);
	EXPECT_EQ(f.grey.size(), cv::Size(static_cast<int>(K.width), static_cast<int>(K.height)));
}
