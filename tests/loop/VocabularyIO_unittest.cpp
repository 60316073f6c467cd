#include <gtest/gtest.h>
#include <keygrid/loop/Vocabulary.h>

#include <TestData.h>
#include <cstring>
#include <sstream>

#include "SyntheticDescriptors.h"

using namespace keygrid::loop;
using keygrid::test::randomBinary;

namespace
{
Vocabulary smallVocabulary(bool binary)
{
	std::mt19937_64 rng(8);
	std::vector<cv::Mat> imgs;
	for (int i = 0; i < 6; ++i)
	{
		if (binary) imgs.push_back(randomBinary(200, 32, rng));
		else
		{
			cv::Mat f(200, 128, CV_32F);
			cv::RNG(static_cast<std::uint64_t>(i + 1)).fill(f, cv::RNG::UNIFORM, 0.f, 1.f);
			imgs.push_back(f);
		}
	}
	VocabularyOptions o;
	o.branching = 5;
	o.levels = 3;
	return Vocabulary::train(imgs, o);
}

void expectSameTransforms(const Vocabulary& a, const Vocabulary& b, const cv::Mat& q)
{
	FeatureVector fa, fb;
	const BowVector va = a.transform(q, fa, 2), vb = b.transform(q, fb, 2);
	ASSERT_EQ(va.size(), vb.size());
	for (std::size_t i = 0; i < va.size(); ++i)
	{
		EXPECT_EQ(va[i].word, vb[i].word);
		EXPECT_EQ(va[i].weight, vb[i].weight);  // bit-identical
	}
	EXPECT_EQ(fa, fb);
}
}  // namespace

TEST(VocabularyIO, BinaryRoundTripGivesIdenticalTransforms)
{
	const Vocabulary v = smallVocabulary(true);
	const std::string path = keygrid::test::scratchDir("loop_vocab_io") + "/vocab.bin";
	v.save(path);
	const Vocabulary r = Vocabulary::load(path);
	EXPECT_EQ(r.numWords(), v.numWords());
	EXPECT_EQ(r.numNodes(), v.numNodes());
	EXPECT_EQ(r.describe(), v.describe());
	std::mt19937_64 rng(99);
	expectSameTransforms(v, r, randomBinary(300, 32, rng));
}

TEST(VocabularyIO, FloatRoundTripGivesIdenticalTransforms)
{
	const Vocabulary v = smallVocabulary(false);
	std::stringstream ss;
	v.save(ss);
	const Vocabulary r = Vocabulary::load(ss);
	cv::Mat q(100, 128, CV_32F);
	cv::RNG(77).fill(q, cv::RNG::UNIFORM, 0.f, 1.f);
	expectSameTransforms(v, r, q);
	EXPECT_EQ(r.descriptorType(), DescriptorType::Float);
	EXPECT_EQ(r.descriptorCols(), 128);
}

TEST(VocabularyIO, UnknownVersionTruncationAndBadMagicThrow)
{
	std::ostringstream os;
	smallVocabulary(true).save(os);
	const std::string good = os.str();

	std::string badVersion = good;
	const std::uint32_t v2 = Vocabulary::kFileVersion + 1;
	std::memcpy(&badVersion[8], &v2, 4);
	std::istringstream a(badVersion);
	try
	{
		Vocabulary::load(a);
		FAIL() << "expected an exception";
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_NE(std::string(e.what()).find("version 2"), std::string::npos) << e.what();
	}

	for (std::size_t cut : {good.size() - 1, good.size() / 2, std::size_t(30), std::size_t(4)})
	{
		std::istringstream t(good.substr(0, cut));
		EXPECT_THROW(Vocabulary::load(t), std::runtime_error) << "cut at " << cut;
	}
	std::string badMagic = good;
	badMagic[0] = 'X';
	std::istringstream m(badMagic);
	EXPECT_THROW(Vocabulary::load(m), std::runtime_error);
	EXPECT_THROW(Vocabulary::load("/nonexistent/vocab.bin"), std::runtime_error);

	std::istringstream ok(good);
	EXPECT_NO_THROW(Vocabulary::load(ok));
}
