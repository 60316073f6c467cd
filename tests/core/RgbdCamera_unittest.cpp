#include <keygrid/core/RgbdCamera.h>
#include <mrpt/config/CConfigFileMemory.h>

#include "TestData.h"

#include <fstream>

using keygrid::core::RgbdCamera;

TEST(RgbdCamera, PresetsCarryPublishedCalibrations)
{
	const auto fr1 = RgbdCamera::Preset("fr1");
	EXPECT_DOUBLE_EQ(fr1.fx, 517.306408);
	EXPECT_DOUBLE_EQ(fr1.cy, 255.313989);
	EXPECT_DOUBLE_EQ(fr1.dist[4], 1.163314);
	EXPECT_TRUE(fr1.hasDistortion());
	EXPECT_FLOAT_EQ(fr1.depthUnits, 1.0f / 5000.0f);
	EXPECT_FALSE(RgbdCamera::Preset("fr3").hasDistortion());
	EXPECT_DOUBLE_EQ(RgbdCamera::Preset("icl").fy, -480.0);
	EXPECT_THROW(RgbdCamera::Preset("fr9"), std::invalid_argument);
}

TEST(RgbdCamera, IniRoundTripAndKeyNamedOnError)
{
	const auto fr2 = RgbdCamera::Preset("fr2");
	mrpt::config::CConfigFileMemory cfg;
	fr2.saveToConfigFile(cfg, "camera");
	RgbdCamera back;
	back.loadFromConfigFile(cfg, "camera");
	EXPECT_DOUBLE_EQ(back.fx, fr2.fx);
	EXPECT_DOUBLE_EQ(back.cx, fr2.cx);
	for (int i = 0; i < 5; i++) EXPECT_DOUBLE_EQ(back.dist[i], fr2.dist[i]);
	EXPECT_EQ(back.name, "fr2");

	mrpt::config::CConfigFileMemory bad;
	bad.write("camera", "fx", "abc");
	try
	{
		back.loadFromConfigFile(bad, "camera");
		FAIL() << "no exception";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_NE(std::string(e.what()).find("fx"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find("abc"), std::string::npos) << e.what();
	}
	mrpt::config::CConfigFileMemory neg;
	neg.write("camera", "depth_units", "-1");
	EXPECT_THROW(back.loadFromConfigFile(neg, "camera"), std::invalid_argument);
}

TEST(RgbdCamera, FromIniFileAndTCameraRoundTrip)
{
	const std::string dir = keygrid::test::scratchDir("camera_ini");
	{
		std::ofstream f(dir + "/mycam.ini");
		f << "[camera]\nfx=500\nfy=501\ncx=320\ncy=240\nk1=0.1\ndepth_units=0.001\n";
	}
	const auto c = RgbdCamera::FromPresetOrFile(dir + "/mycam.ini");
	EXPECT_DOUBLE_EQ(c.fy, 501.0);
	EXPECT_FLOAT_EQ(c.depthUnits, 0.001f);
	EXPECT_THROW(RgbdCamera::FromPresetOrFile(dir + "/missing.ini"), std::invalid_argument);

	const auto t = c.toTCamera();
	EXPECT_EQ(t.distortion, mrpt::img::DistortionModel::plumb_bob);
	const auto back = RgbdCamera::FromTCamera(t, c.depthUnits);
	EXPECT_DOUBLE_EQ(back.fx, c.fx);
	EXPECT_DOUBLE_EQ(back.dist[0], 0.1);
	EXPECT_EQ(back.width, 640u);
}
