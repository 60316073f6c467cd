#include <keygrid/core/TimestampAssociation.h>
#include <keygrid/core/TumFrameSource.h>

#include "SyntheticTum.h"
#include "TestData.h"

#include <fstream>
#include <opencv2/imgcodecs.hpp>

using namespace keygrid::core;

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
