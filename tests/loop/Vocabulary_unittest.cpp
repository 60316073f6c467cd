#include <gtest/gtest.h>
#include <keygrid/loop/DirectIndexMatcher.h>
#include <keygrid/loop/KeyFrameDatabase.h>
#include <keygrid/loop/Vocabulary.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <algorithm>
#include <map>
#include <set>
#include <sstream>

#include "SyntheticDescriptors.h"

using namespace keygrid::loop;
using keygrid::test::addNoise;
using keygrid::test::flipBits;
using keygrid::test::randomBinary;
using keygrid::test::randomBinaryVocabulary;
using keygrid::test::sampleImage;

namespace
{
struct Clustered
{
	std::vector<cv::Mat> images;  //!< one "image" per cluster sample block
	cv::Mat all;
	std::vector<int> label;  //!< cluster of each row of `all`
};

/** `clusters` groups of `perCluster` descriptors around random centres, split into 10 images. */
Clustered makeClusters(bool binary, int clusters, int perCluster, std::uint64_t seed)
{
	std::mt19937_64 rng(seed);
	Clustered c;
	cv::Mat centres;
	if (binary) centres = randomBinary(clusters, 32, rng);
	else
	{
		centres.create(clusters, 128, CV_32F);
		cv::RNG cvr(static_cast<std::uint64_t>(seed));
		cvr.fill(centres, cv::RNG::UNIFORM, 0.f, 100.f);
	}
	std::vector<cv::Mat> rows;
	for (int k = 0; k < clusters; ++k)
		for (int i = 0; i < perCluster; ++i)
		{
			// Binary: 12 of 256 bits flipped (centres differ in ~128 bits). Float: sigma 2 around
			// centres ~290 apart on average.
			rows.push_back(binary ? flipBits(centres.row(k), 12, rng) : addNoise(centres.row(k), 2.f, rng));
			c.label.push_back(k);
		}
	cv::vconcat(rows, c.all);
	// Interleave the rows into 10 images (each image holds members of every cluster).
	for (int img = 0; img < 10; ++img)
	{
		std::vector<cv::Mat> part;
		for (int r = img; r < c.all.rows; r += 10) part.push_back(c.all.row(r));
		cv::Mat m;
		cv::vconcat(part, m);
		c.images.push_back(m);
	}
	return c;
}

/** A vocabulary trained on the images of clusters, and how its words split them. */
struct ClusterWords
{
	Vocabulary v;
	std::map<WordId, std::set<int>> labelsOfWord;    //!< word -> cluster labels of its members
	std::map<int, std::set<WordId>> wordsOfCluster;  //!< cluster -> its members' words
};

/** `makeClusters(binary, clusters, perCluster, seed)` through a `branching` x `levels` tree. */
ClusterWords trainOnClusters(bool binary, int clusters, int perCluster, std::uint64_t seed, int branching, int levels)
{
	const Clustered c = makeClusters(binary, clusters, perCluster, seed);
	VocabularyOptions o;
	o.branching = branching;
	o.levels = levels;
	ClusterWords t{Vocabulary::train(c.images, o), {}, {}};
	for (int r = 0; r < c.all.rows; ++r)
	{
		const WordId w = t.v.wordOf(c.all.row(r));
		t.labelsOfWord[w].insert(c.label[static_cast<std::size_t>(r)]);
		t.wordsOfCluster[c.label[static_cast<std::size_t>(r)]].insert(w);
	}
	return t;
}
}  // namespace

class VocabularyClusters : public ::testing::TestWithParam<bool>
{
};

TEST_P(VocabularyClusters, OneLevelTreeRecoversTheClusters)
{
	const bool binary = GetParam();
	const auto [v, labelsOfWord, wordsOfCluster] = trainOnClusters(binary, 8, 40, 7, 8, 1);
	EXPECT_EQ(v.numWords(), 8u);
	EXPECT_EQ(v.descriptorType(), binary ? DescriptorType::Binary : DescriptorType::Float);
	// A bijection: every cluster is exactly one word and every word exactly one cluster.
	ASSERT_EQ(wordsOfCluster.size(), 8u);
	for (const auto& [k, words] : wordsOfCluster) EXPECT_EQ(words.size(), 1u) << "cluster " << k;
	for (const auto& [w, labels] : labelsOfWord) EXPECT_EQ(labels.size(), 1u) << "word " << w;
}

TEST_P(VocabularyClusters, DeeperTreeKeepsEveryWordPure)
{
	// 27 clusters with k = 4, L = 3 (64 leaves): level 1 sees groups of clusters; every leaf
	// must still hold the members of one cluster only.
	const auto [v, labelsOfWord, wordsOfCluster] = trainOnClusters(GetParam(), 27, 20, 11, 4, 3);
	std::size_t mixed = 0;
	for (const auto& [w, labels] : labelsOfWord) mixed += labels.size() > 1;
	EXPECT_EQ(mixed, 0u);
	// Every cluster is found; splitting one over a few words is allowed (k^L > #clusters).
	EXPECT_EQ(wordsOfCluster.size(), 27u);
	std::size_t words = 0;
	for (const auto& [k, w] : wordsOfCluster) words += w.size();
	EXPECT_LE(words, 27u * 3);
}

INSTANTIATE_TEST_SUITE_P(BinaryAndFloat, VocabularyClusters, ::testing::Values(true, false));

TEST(Vocabulary, TrainingIsDeterministicForAnyThreadCount)
{
	std::mt19937_64 rng(3);
	std::vector<cv::Mat> imgs;
	for (int i = 0; i < 10; ++i) imgs.push_back(randomBinary(500, 32, rng));
	VocabularyOptions o;
	o.branching = 5;
	o.levels = 3;
	o.threads = 1;
	std::ostringstream a, b;
	Vocabulary::train(imgs, o).save(a);
	o.threads = 2;
	Vocabulary::train(imgs, o).save(b);
	EXPECT_TRUE(a.str() == b.str());
	o.seed = 2;
	std::ostringstream c;
	Vocabulary::train(imgs, o).save(c);
	EXPECT_FALSE(a.str() == c.str());
}

TEST(Vocabulary, IdfWeightsAreLogOfDocumentFrequency)
{
	const auto c = makeClusters(true, 4, 10, 5);
	// 4 images: image i holds clusters 0..i, so cluster k appears in 4 - k images.
	std::vector<cv::Mat> imgs;
	for (int i = 0; i < 4; ++i)
	{
		std::vector<cv::Mat> rows;
		for (int r = 0; r < c.all.rows; ++r)
			if (c.label[static_cast<std::size_t>(r)] <= i) rows.push_back(c.all.row(r));
		cv::Mat m;
		cv::vconcat(rows, m);
		imgs.push_back(m);
	}
	VocabularyOptions o;
	o.branching = 4;
	o.levels = 1;
	const Vocabulary v = Vocabulary::train(imgs, o);
	ASSERT_EQ(v.numWords(), 4u);
	EXPECT_EQ(v.trainingImages(), 4u);
	for (int k = 0; k < 4; ++k)
	{
		const int row = k * 10;
		const WordId w = v.wordOf(c.all.row(row));
		EXPECT_NEAR(v.idf(w), std::log(4.0 / (4 - k)), 1e-12) << "cluster " << k;
	}
	// TF-IDF: an image with 10 descriptors of cluster 1 and 10 of cluster 3 weighs the words
	// log(4/3) : log(4/1), then L1-normalised.
	cv::Mat q;
	cv::vconcat(c.all.rowRange(10, 20), c.all.rowRange(30, 40), q);
	const BowVector bv = v.transform(q);
	ASSERT_EQ(bv.size(), 2u);
	const double a = std::log(4.0 / 3.0), b = std::log(4.0);
	const WordId w1 = v.wordOf(c.all.row(10));
	for (const auto& e : bv) EXPECT_NEAR(e.weight, (e.word == w1 ? a : b) / (a + b), 1e-12);
	// Cluster 0 is in every image: idf 0, the word is dropped.
	EXPECT_TRUE(v.transform(c.all.rowRange(0, 10)).empty());
}

TEST(Vocabulary, NoisyCopyOfAnImageRanksFirstAmongDistractors)
{
	std::mt19937_64 rng(21);
	const cv::Mat pool = randomBinary(3000, 32, rng);  // the "world's" distinct features
	std::vector<cv::Mat> training;
	for (int i = 0; i < 60; ++i) training.push_back(sampleImage(pool, 200, 6, rng));
	VocabularyOptions o;
	o.branching = 10;
	o.levels = 3;
	const Vocabulary v = Vocabulary::train(training, o);

	std::vector<cv::Mat> images;
	KeyFrameDatabase db;
	for (int i = 0; i < 150; ++i)
	{
		images.push_back(sampleImage(pool, 200, 6, rng));
		db.add(static_cast<KeyFrameId>(i), v.transform(images.back()));
	}
	for (int target : {0, 37, 88, 149})
	{
		// Noisy revisit: 8 more bit flips per descriptor, a quarter of the features replaced.
		cv::Mat q = flipBits(images[static_cast<std::size_t>(target)], 8, rng);
		sampleImage(pool, 50, 6, rng).copyTo(q.rowRange(0, 50));
		const BowVector bq = v.transform(q);
		const auto res = db.query(bq, DatabaseQuery{5, 0.0, 0.0, 1.0, 0.0, {}});
		ASSERT_FALSE(res.empty());
		EXPECT_EQ(res[0].id, static_cast<KeyFrameId>(target));
		ASSERT_GE(res.size(), 2u);
		EXPECT_GT(res[0].score, 2.0 * res[1].score) << "own copy " << res[0].score << ", best distractor " << res[1].score;
		// The inverted index computes exactly the L1 score.
		EXPECT_NEAR(res[0].score, l1Score(bq, db.bow(res[0].id)), 1e-12);
	}
}

TEST(Vocabulary, DirectIndexGroupsFeaturesByNodeAtTheRequestedLevel)
{
	std::mt19937_64 rng(4);
	const Vocabulary v = randomBinaryVocabulary(5, 400, 6, 3, rng);
	const cv::Mat q = randomBinary(300, 32, rng);
	FeatureVector fv;
	const BowVector a = v.transform(q, fv, 2);
	const BowVector b = v.transform(q);
	ASSERT_EQ(a.size(), b.size());
	for (std::size_t i = 0; i < a.size(); ++i)
	{
		EXPECT_EQ(a[i].word, b[i].word);
		EXPECT_DOUBLE_EQ(a[i].weight, b[i].weight);
	}
	std::vector<int> seen(300, 0);
	for (const auto& [node, feats] : fv)
	{
		EXPECT_LE(v.nodeDepth(node), 2);
		for (int f : feats) ++seen[static_cast<std::size_t>(f)];
	}
	for (int s : seen) EXPECT_EQ(s, 1);
	// Features sharing a word share their level-2 node.
	std::map<WordId, NodeId> nodeOfWord;
	for (const auto& [node, feats] : fv)
		for (int f : feats)
		{
			const WordId w = v.wordOf(q.row(f));
			const auto it = nodeOfWord.emplace(w, node).first;
			EXPECT_EQ(it->second, node);
		}
	double sum = 0;
	for (const auto& e : a) sum += e.weight;
	EXPECT_NEAR(sum, 1.0, 1e-12);
}

TEST(Vocabulary, RejectsBadInput)
{
	EXPECT_THROW(Vocabulary::train({}), std::invalid_argument);
	std::mt19937_64 rng(1);
	std::vector<cv::Mat> mixed{randomBinary(10, 32, rng), cv::Mat(10, 32, CV_32F, cv::Scalar(0))};
	EXPECT_THROW(Vocabulary::train(mixed), std::invalid_argument);
	VocabularyOptions o;
	o.branching = 1;
	EXPECT_THROW(Vocabulary::train({randomBinary(10, 32, rng)}, o), std::invalid_argument);
	const Vocabulary v = Vocabulary::train({randomBinary(50, 32, rng)});
	EXPECT_THROW(v.transform(randomBinary(3, 16, rng)), std::invalid_argument);
	EXPECT_THROW(Vocabulary().transform(randomBinary(3, 32, rng)), std::logic_error);
}

namespace
{
/** The message of the std::invalid_argument that loading `ini` section [vocab] throws ("" if none). */
std::string loadError(const std::string& ini)
{
	try
	{
		VocabularyOptions().loadFromConfigFile(mrpt::config::CConfigFileMemory(ini), "vocab");
	}
	catch (const std::invalid_argument& e)
	{
		return e.what();
	}
	return "";
}
}  // namespace

TEST(VocabularyOptions, ConfigRoundTripAndInvalidKey)
{
	VocabularyOptions o;
	o.branching = 7;
	o.levels = 5;
	o.maxIterations = 3;
	o.seed = 99;
	o.threads = 2;
	mrpt::config::CConfigFileMemory cfg;
	o.saveToConfigFile(cfg, "vocab");
	// Padded keys written by saveToConfigFile are read back from the text (as from a file).
	std::string text;
	cfg.getContent(text);
	EXPECT_NE(text.find("k: children per node"), std::string::npos) << text;
	VocabularyOptions r;
	r.loadFromConfigFile(mrpt::config::CConfigFileMemory(text), "vocab");
	EXPECT_EQ(r.branching, 7);
	EXPECT_EQ(r.levels, 5);
	EXPECT_EQ(r.maxIterations, 3);
	EXPECT_EQ(r.seed, 99u);
	EXPECT_EQ(r.threads, 2);

	// A value its rule refuses, a malformed one (read strictly), and too many words.
	const std::string none = "[vocab]\n";
	EXPECT_EQ(loadError(none + "levels = 0\n"), "[vocab] levels = 0 (must be >= 1)");
	EXPECT_EQ(loadError(none + "branching = 1\n"), "[vocab] branching = 1 (must be >= 2)");
	EXPECT_EQ(loadError(none + "threads = -1\n"), "[vocab] threads = -1 (must be >= 0)");
	EXPECT_NE(loadError(none + "max_iterations = 5x\n").find("[vocab] max_iterations"), std::string::npos);
	EXPECT_NE(loadError(none + "seed = -3\n").find("[vocab] seed"), std::string::npos);
	EXPECT_NE(loadError(none + "branching = 10\nlevels = 10\n").find("[vocab] branching = 10, levels = 10"), std::string::npos);
	EXPECT_EQ(loadError(none + "branching = 2\nlevels = 31\n"), "");
	EXPECT_NE(loadError(none + "branching = 2\nlevels = 32\n"), "");
	EXPECT_NO_THROW(VocabularyOptions{}.validate());
}

TEST(DirectIndexMatcher, RecoversAPermutationOfNoisyDescriptors)
{
	std::mt19937_64 rng(31);
	const Vocabulary v = randomBinaryVocabulary(5, 400, 8, 3, rng);
	// B = A shuffled, 5 bits flipped per descriptor, plus 100 unrelated descriptors.
	const cv::Mat A = randomBinary(300, 32, rng);
	std::vector<int> perm(300);
	for (int i = 0; i < 300; ++i) perm[static_cast<std::size_t>(i)] = i;
	std::shuffle(perm.begin(), perm.end(), rng);
	cv::Mat B(400, 32, CV_8U);
	for (int i = 0; i < 300; ++i) A.row(i).copyTo(B.row(perm[static_cast<std::size_t>(i)]));
	randomBinary(100, 32, rng).copyTo(B.rowRange(300, 400));
	B = flipBits(B, 5, rng);
	FeatureVector fa, fb;
	v.transform(A, fa, 1);
	v.transform(B, fb, 1);
	const auto matches = matchByDirectIndex(A, fa, B, fb);
	int correct = 0;
	for (const auto& m : matches) correct += perm[static_cast<std::size_t>(m.a)] == m.b;
	// Every returned match must be right. Uniformly random descriptors are the worst case for a
	// tree (all nearly equidistant to the centres), so 5 flipped bits move some of them to
	// another level-1 node: still at least two thirds are found.
	EXPECT_EQ(correct, static_cast<int>(matches.size()));
	EXPECT_GT(matches.size(), 200u);
	for (const auto& m : matches) EXPECT_LE(m.distance, 5.0);
}
