#include <gtest/gtest.h>
#include <keygrid/loop/Vocabulary.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <TestData.h>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <utility>
#include <vector>

using keygrid::test::runCommand;
using keygrid::test::scratchDir;
using keygrid::test::toolPath;

namespace
{
/** A textured image: random filled rectangles and circles of random grey levels. */
cv::Mat proceduralImage(std::uint64_t seed)
{
	std::mt19937_64 rng(seed);
	std::uniform_int_distribution<int> x(0, 319), y(0, 239), r(4, 30), g(0, 255);
	cv::Mat img(240, 320, CV_8U, cv::Scalar(128));
	for (int i = 0; i < 120; ++i)
	{
		if (i % 2) cv::rectangle(img, cv::Rect(x(rng), y(rng), r(rng), r(rng)), cv::Scalar(g(rng)), cv::FILLED);
		else cv::circle(img, cv::Point(x(rng), y(rng)), r(rng), cv::Scalar(g(rng)), cv::FILLED);
	}
	return img;
}
}  // namespace

TEST(VocabApp, TrainsOnAnImageFolderAndDescribesTheResult)
{
	const std::string dir = scratchDir("loop_vocab_app");
	const std::string images = dir + "/images";
	std::filesystem::create_directories(images);
	for (int i = 0; i < 6; ++i) cv::imwrite(images + "/img" + std::to_string(i) + ".png", proceduralImage(100 + i));
	const std::string out = dir + "/vocab.bin";
	std::string log;
	ASSERT_EQ(runCommand(toolPath("keygrid-vocab") + " train --images " + images + " --output " + out + " --k 6 --levels 3", &log), 0) << log;
	const auto v = keygrid::loop::Vocabulary::load(out);
	EXPECT_EQ(v.trainingImages(), 6u);
	EXPECT_EQ(v.branching(), 6);
	EXPECT_EQ(v.descriptorCols(), 32);
	EXPECT_GT(v.numWords(), 36u);
	ASSERT_EQ(runCommand(toolPath("keygrid-vocab") + " info " + out, &log), 0) << log;
	EXPECT_NE(log.find(std::to_string(v.numWords()) + " words"), std::string::npos) << log;

	// An image list (relative paths, comments) and --every / --max-images select the same images.
	{
		std::ofstream list(dir + "/list.txt");
		list << "# training images\n";
		for (int i = 0; i < 6; ++i) list << "images/img" << i << ".png\n";
	}
	ASSERT_EQ(runCommand(toolPath("keygrid-vocab") + " train --images " + dir + "/list.txt --every 2 --max-images 2 --output " + out + " --k 6 --levels 3", &log), 0) << log;
	EXPECT_EQ(keygrid::loop::Vocabulary::load(out).trainingImages(), 2u);
}

TEST(VocabApp, BadCommandLinesFailWithOneLine)
{
	std::string log;
	EXPECT_EQ(runCommand(toolPath("keygrid-vocab") + " --help", &log), 0);
	EXPECT_NE(log.find("--levels"), std::string::npos);
	EXPECT_EQ(runCommand(toolPath("keygrid-vocab") + " frobnicate", &log), 2);
	EXPECT_NE(log.find("unknown sub-command 'frobnicate'"), std::string::npos) << log;
	EXPECT_NE(runCommand(toolPath("keygrid-vocab") + " train --output /tmp/x.bin", &log), 0);
	EXPECT_NE(log.find("exactly one of"), std::string::npos) << log;
	EXPECT_NE(runCommand(toolPath("keygrid-vocab") + " info /nonexistent.bin", &log), 0);
	EXPECT_NE(log.find("/nonexistent.bin"), std::string::npos) << log;
	EXPECT_NE(runCommand(toolPath("keygrid-vocab") + " train --images . --features surf --output /tmp/x.bin", &log), 0);
	EXPECT_NE(log.find("surf"), std::string::npos) << log;
	// Training options are checked by the vocabulary options' rules, naming the option.
	const std::vector<std::pair<std::string, std::string>> badOptions{
		{"--k 1", "--k 1 (must be >= 2)"}, {"--threads -2", "--threads -2 (must be >= 0)"}, {"--k 10 --levels 10", "branching = 10, levels = 10"}};
	for (const auto& [options, message] : badOptions)
	{
		EXPECT_EQ(runCommand(toolPath("keygrid-vocab") + " train --images . " + options + " --output /tmp/x.bin", &log), 2) << options;
		EXPECT_NE(log.find(message), std::string::npos) << log;
	}
}

TEST(VocabApp, ReadsARawlogAndRefusesToTrainOnOneImage)
{
	// The rawlog's one frame is read (its descriptors extracted), but one image gives every
	// word the idf weight 0: refused, and no file written.
	const std::string rawlog = keygrid::test::mrptDatasetsDir() + "/tests_rgbd.rawlog";
	if (!std::filesystem::exists(rawlog)) GTEST_SKIP() << rawlog << " not installed";
	const std::string out = scratchDir("loop_vocab_app_rawlog") + "/vocab.bin";
	std::filesystem::remove(out);
	std::string log;
	EXPECT_EQ(runCommand(toolPath("keygrid-vocab") + " train --rawlog " + rawlog + " --output " + out + " --k 5 --levels 2", &log), 1) << log;
	EXPECT_NE(log.find("at least 2 images with features, got 1"), std::string::npos) << log;
	EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(VocabApp, RefusesImagesThatGiveNoWordAWeight)
{
	// Six copies of one image: every word is in every image.
	const std::string dir = scratchDir("loop_vocab_app_same");
	const std::string images = dir + "/images";
	std::filesystem::create_directories(images);
	for (int i = 0; i < 6; ++i) cv::imwrite(images + "/img" + std::to_string(i) + ".png", proceduralImage(7));
	const std::string out = dir + "/vocab.bin";
	std::filesystem::remove(out);
	std::string log;
	EXPECT_EQ(runCommand(toolPath("keygrid-vocab") + " train --images " + images + " --output " + out + " --k 4 --levels 2", &log), 1) << log;
	EXPECT_NE(log.find("every word weighs 0"), std::string::npos) << log;
	EXPECT_FALSE(std::filesystem::exists(out));
}
