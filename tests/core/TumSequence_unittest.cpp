#include <keygrid/core/TimestampAssociation.h>
#include <keygrid/core/TumFrameSource.h>

#include "SyntheticTum.h"
#include "TestChecks.h"
#include "TestData.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

using namespace keygrid::core;
using keygrid::test::errorOf;

TEST(TimestampAssociation, NearestUniqueWithinTolerance)
{
	const std::vector<double> a = {0.0, 0.033, 0.066, 0.100, 0.500};
	const std::vector<double> b = {0.031, 0.004, 0.070, 0.067, 0.45};
	const auto m = associateTimestamps(a, b, 0.02);
	ASSERT_EQ(m.size(), 3u);  // 0.100 only has 0.070/0.067 (taken or > 20 ms); 0.500 none
	EXPECT_EQ(m[0], std::make_pair(std::size_t(0), std::size_t(1)));
	EXPECT_EQ(m[1], std::make_pair(std::size_t(1), std::size_t(0)));
	EXPECT_EQ(m[2], std::make_pair(std::size_t(2), std::size_t(3)));  // 1 ms beats 4 ms
}

TEST(TumSequence, AssociationsFileAndListsGiveTheSamePairs)
{
	const auto s = keygrid::test::writeSyntheticTum(keygrid::test::scratchDir("tumseq_assoc"), 5);
	const TumSequence withAssoc(s.dir);
	EXPECT_EQ(withAssoc.indexSource(), "associations.txt");
	std::remove((s.dir + "/associations.txt").c_str());
	const TumSequence fromLists(s.dir);
	EXPECT_EQ(fromLists.indexSource(), "rgb.txt+depth.txt");
	ASSERT_EQ(withAssoc.pairs().size(), 5u);
	ASSERT_EQ(fromLists.pairs().size(), 5u);
	for (std::size_t i = 0; i < 5; i++)
	{
		EXPECT_EQ(withAssoc.pairs()[i].rgbPath, fromLists.pairs()[i].rgbPath);
		EXPECT_EQ(withAssoc.pairs()[i].depthPath, fromLists.pairs()[i].depthPath);
		EXPECT_NEAR(fromLists.pairs()[i].tDepth - fromLists.pairs()[i].tRgb, 0.004, 1e-6);
	}
	// A 15 ms lag (18 ms to the next colour frame): no pair within 10 ms -> a clear error;
	// within 20 ms each depth goes to its own colour frame, the nearer one.
	const auto lag = keygrid::test::writeSyntheticTum(keygrid::test::scratchDir("tumseq_lag"), 3, 8, 6, false, 0.015);
	EXPECT_THROW(TumSequence(lag.dir, 0.01), std::runtime_error);
	const TumSequence lagged(lag.dir, 0.02);
	ASSERT_EQ(lagged.pairs().size(), 3u);
	for (const auto& p : lagged.pairs()) EXPECT_NEAR(p.tDepth - p.tRgb, 0.015, 1e-6);
}

TEST(TumSequence, BrokenLinesAreSkippedAndReported)
{
	const auto s = keygrid::test::writeSyntheticTum(keygrid::test::scratchDir("tumseq_broken"), 3, 8, 6, false);
	std::ofstream(s.dir + "/rgb.txt", std::ios::app) << "garbage line here\n12.5\n";
	const TumSequence seq(s.dir);
	EXPECT_EQ(seq.pairs().size(), 3u);
	ASSERT_EQ(seq.issues().size(), 2u);
	EXPECT_EQ(seq.issues()[0].line, 7u);
}

TEST(TumSequence, MissingFolderListsAndImagesAreClearErrors)
{
	EXPECT_THROW(TumSequence("/nonexistent/keygrid"), std::runtime_error);
	const std::string empty = keygrid::test::scratchDir("tumseq_empty");
	try
	{
		TumSequence{empty};
		FAIL();
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_NE(std::string(e.what()).find("rgb.txt"), std::string::npos) << e.what();
	}
	std::ofstream(empty + "/rgb.txt") << "# nothing\n";
	std::ofstream(empty + "/depth.txt") << "# nothing\n";
	EXPECT_THROW(TumSequence{empty}, std::runtime_error);

	const auto s = keygrid::test::writeSyntheticTum(keygrid::test::scratchDir("tumseq_missing_png"), 2, 8, 6);
	std::remove((s.dir + "/" + TumSequence(s.dir).pairs()[1].depthPath.substr(s.dir.size() + 1)).c_str());
	FrameSourceOptions o;
	o.camera = RgbdCamera::Preset("kinect");
	o.camera->width = 8;
	o.camera->height = 6;
	TumFrameSource src(s.dir, o);
	Frame f;
	EXPECT_TRUE(src.next(f));
	try
	{
		src.next(f);
		FAIL();
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_NE(std::string(e.what()).find("missing image"), std::string::npos) << e.what();
	}
}

TEST(TumSequence, SizeAndTypeMismatchesAreClearErrors)
{
	const auto s = keygrid::test::writeSyntheticTum(keygrid::test::scratchDir("tumseq_size"), 1, 8, 6);
	FrameSourceOptions o;
	o.camera = RgbdCamera::Preset("kinect");  // 640x480 but images are 8x6
	TumFrameSource src(s.dir, o);
	Frame f;
	try
	{
		src.next(f);
		FAIL();
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_NE(std::string(e.what()).find("8x6"), std::string::npos) << e.what();
	}
	// A colour PNG where depth should be: not 16-bit.
	const auto pair = TumSequence(s.dir).pairs()[0];
	cv::imwrite(pair.depthPath, s.colour[0]);
	o.camera->width = 8;
	o.camera->height = 6;
	TumFrameSource src2(s.dir, o);
	EXPECT_THROW(src2.next(f), std::runtime_error);
	// An unreadable PNG.
	std::ofstream(pair.rgbPath) << "not a png";
	TumFrameSource src3(s.dir, o);
	EXPECT_THROW(src3.next(f), std::runtime_error);
}

TEST(TumSequence, SharedFr1DeskIsIndexedWithFr1Camera)
{
	KEYGRID_SKIP_WITHOUT_SHARED_DATA("tum_fr1_desk_9frames");
	TumFrameSource src(keygrid::test::sharedDataDir() + "/tum_fr1_desk_9frames");
	EXPECT_EQ(src.sizeHint().value(), 9u);
	EXPECT_EQ(src.camera().name, "fr1");
	Frame f;
	std::size_t n = 0;
	double median = 0;
	while (src.next(f))
	{
		++n;
		EXPECT_EQ(f.grey.size(), cv::Size(640, 480));
		std::vector<float> v;
		for (int r = 0; r < f.depth.rows; r += 4)
			for (int c = 0; c < f.depth.cols; c += 4)
				if (f.depth.at<float>(r, c) > 0) v.push_back(f.depth.at<float>(r, c));
		ASSERT_FALSE(v.empty());
		std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
		median = v[v.size() / 2];
		EXPECT_GT(median, 0.4);  // a desk seen from ~1 m
		EXPECT_LT(median, 3.0);
	}
	EXPECT_EQ(n, 9u);
}

TEST(TumSequence, DepthIgnoredReadsTheColourImagesAloneWithoutOpeningDepth)
{
	const auto s = keygrid::test::writeSyntheticTum(keygrid::test::scratchDir("tumseq_mono"), 3, 8, 6);
	FrameSourceOptions rgbd;
	rgbd.camera = RgbdCamera::Preset("fr1");
	rgbd.camera->width = 8;
	rgbd.camera->height = 6;
	FrameSourceOptions mono = rgbd;
	mono.depth = DepthUse::Ignore;
	// The same images, timestamps and camera as in RGB-D mode, without depth (a reused frame
	// keeps no stale depth).
	{
		TumFrameSource a(s.dir, rgbd), b(s.dir, mono);
		EXPECT_EQ(b.sequence().indexSource(), "rgb.txt");
		EXPECT_FALSE(b.sequence().hasDepth());
		EXPECT_NE(b.describe().find("3 images from rgb.txt, depth ignored"), std::string::npos) << b.describe();
		Frame fa, fb;
		for (int i = 0; i < 3; i++)
		{
			ASSERT_TRUE(a.next(fa));
			fb = fa;
			ASSERT_TRUE(b.next(fb));
			EXPECT_FALSE(fb.hasDepth());
			EXPECT_TRUE(fb.depthRaw.empty());
			EXPECT_EQ(cv::norm(fb.colour, s.colour[i], cv::NORM_INF), 0.0);
			EXPECT_EQ(cv::norm(fb.grey, fa.grey, cv::NORM_INF), 0.0);
			EXPECT_EQ(fb.timestamp, fa.timestamp);
			EXPECT_NEAR(fb.timestamp, s.tRgb[i], 1e-6);  // rgb.txt holds microseconds
			EXPECT_EQ(fb.camera.fx, fa.camera.fx);
		}
		EXPECT_FALSE(b.next(fb));
	}
	// Depth PNGs that cannot be decoded are never opened.
	const TumSequence pairs(s.dir);
	for (const auto& p : pairs.pairs()) std::ofstream(p.depthPath) << "not a png";
	{
		TumFrameSource b(s.dir, mono);
		Frame f;
		for (int i = 0; i < 3; i++) ASSERT_TRUE(b.next(f));
		TumFrameSource a(s.dir, rgbd);
		EXPECT_THROW(a.next(f), std::runtime_error);
	}
	// Only associations.txt lists the images: its colour column.
	std::remove((s.dir + "/rgb.txt").c_str());
	{
		TumFrameSource b(s.dir, mono);
		EXPECT_EQ(b.sequence().indexSource(), "associations.txt");
		Frame f;
		ASSERT_TRUE(b.next(f));
		EXPECT_EQ(cv::norm(f.colour, s.colour[0], cv::NORM_INF), 0.0);
		EXPECT_FALSE(f.hasDepth());
	}
	// No list of colour images: an error naming the folder.
	std::remove((s.dir + "/associations.txt").c_str());
	const std::string noList = errorOf<std::runtime_error>([&] { TumFrameSource b(s.dir, mono); });
	EXPECT_NE(noList.find("'" + s.dir + "' has neither rgb.txt nor associations.txt"), std::string::npos) << noList;
}

TEST(TumSequence, FolderWithoutDepthIsAnImageOnlyInput)
{
	// rgb.txt and rgb/ alone, as a monocular camera's TUM folder.
	const auto s = keygrid::test::writeSyntheticTum(keygrid::test::scratchDir("tumseq_rgbonly"), 2, 8, 6, false);
	std::filesystem::remove_all(s.dir + "/depth");
	std::remove((s.dir + "/depth.txt").c_str());
	FrameSourceOptions o;
	o.camera = RgbdCamera::Preset("kinect");
	o.camera->width = 8;
	o.camera->height = 6;
	o.depth = DepthUse::Ignore;
	TumFrameSource src(s.dir, o);
	EXPECT_EQ(src.sizeHint().value(), 2u);
	Frame f;
	ASSERT_TRUE(src.next(f));
	EXPECT_EQ(cv::norm(f.colour, s.colour[0], cv::NORM_INF), 0.0);
	EXPECT_NEAR(f.timestamp, s.tRgb[0], 1e-6);
	EXPECT_FALSE(f.hasDepth());
	// Asked for depth: an error naming the folder and what is missing.
	o.depth = DepthUse::Use;
	const std::string noDepth = errorOf<std::runtime_error>([&] { TumFrameSource rgbd(s.dir, o); });
	EXPECT_NE(noDepth.find("'" + s.dir + "' has neither associations.txt nor depth.txt"), std::string::npos) << noDepth;
	// A missing colour image names the file, as in RGB-D mode.
	std::remove(TumSequence(s.dir, 0.02, DepthUse::Ignore).pairs()[1].rgbPath.c_str());
	o.depth = DepthUse::Ignore;
	TumFrameSource gap(s.dir, o);
	ASSERT_TRUE(gap.next(f));
	const std::string missing = errorOf<std::runtime_error>([&] { gap.next(f); });
	EXPECT_NE(missing.find("missing image '" + s.dir + "/rgb/"), std::string::npos) << missing;
	// An empty rgb.txt gives no image: an error naming the folder.
	std::ofstream(s.dir + "/rgb.txt") << "# nothing\n";
	const std::string none = errorOf<std::runtime_error>([&] { TumSequence(s.dir, 0.02, DepthUse::Ignore); });
	EXPECT_NE(none.find("'" + s.dir + "': rgb.txt gives no colour image"), std::string::npos) << none;
}
