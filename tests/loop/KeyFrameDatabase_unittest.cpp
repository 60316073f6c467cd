#include <gtest/gtest.h>
#include <keygrid/loop/KeyFrameDatabase.h>

#include <random>

using namespace keygrid::loop;

namespace
{
/** Random canonical BoW vector over `vocabSize` words with `n` distinct words. */
BowVector randomBow(std::mt19937_64& rng, WordId vocabSize, int n)
{
	std::uniform_int_distribution<WordId> w(0, vocabSize - 1);
	std::uniform_real_distribution<double> weight(0.1, 1.0);
	BowVector v;
	for (int i = 0; i < n; ++i) v.push_back(BowEntry{w(rng), weight(rng)});
	canonicalise(v);
	normaliseL1(v);
	return v;
}

/** Adds `count` random vectors (randomBow(rng, vocabSize, words)) to `db` as keyframes
 * firstId, firstId + 1, ...; returns them in that order. */
std::vector<BowVector> addRandomKeyFrames(
	KeyFrameDatabase& db, std::mt19937_64& rng, int count, KeyFrameId firstId, WordId vocabSize, int words)
{
	std::vector<BowVector> stored;
	for (int i = 0; i < count; ++i)
	{
		stored.push_back(randomBow(rng, vocabSize, words));
		db.add(firstId + static_cast<KeyFrameId>(i), stored.back());
	}
	return stored;
}
}  // namespace

TEST(BowVector, L1ScoreClosedForms)
{
	const BowVector a{{1, 0.5}, {2, 0.5}};
	const BowVector b{{2, 0.5}, {3, 0.5}};
	// |a - b|_1 = 0.5 + 0 + 0.5 = 1  ->  s = 1 - 0.5 = 0.5
	EXPECT_NEAR(l1Score(a, b), 0.5, 1e-15);
	EXPECT_NEAR(l1Score(a, a), 1.0, 1e-15);
	EXPECT_NEAR(l1Score(a, BowVector{{7, 1.0}}), 0.0, 1e-15);
	// Not normalised inputs are normalised on the fly.
	EXPECT_NEAR(l1Score(BowVector{{1, 2.0}, {2, 2.0}}, b), 0.5, 1e-15);
	BowVector d{{5, 1.0}, {2, 1.0}, {5, 2.0}};
	canonicalise(d);
	ASSERT_EQ(d.size(), 2u);
	EXPECT_EQ(d[0].word, 2u);
	EXPECT_EQ(d[1].weight, 3.0);
}

TEST(KeyFrameDatabase, QueryMatchesBruteForceScoresAndRanking)
{
	std::mt19937_64 rng(5);
	KeyFrameDatabase db;
	const std::vector<BowVector> stored = addRandomKeyFrames(db, rng, 200, 1000, 500, 60);
	const BowVector q = randomBow(rng, 500, 60);
	DatabaseQuery opt;
	opt.maxResults = 0;
	opt.minCommonWordsRatio = 0;
	const auto res = db.query(q, opt);
	std::size_t sharing = 0;
	for (int i = 0; i < 200; ++i)
		if (l1Score(q, stored[static_cast<std::size_t>(i)]) > 0) ++sharing;
	ASSERT_EQ(res.size(), sharing);
	for (std::size_t i = 0; i < res.size(); ++i)
	{
		EXPECT_NEAR(res[i].score, l1Score(q, stored[res[i].id - 1000]), 1e-12);
		if (i > 0) { EXPECT_GE(res[i - 1].score, res[i].score); }
	}
}

TEST(KeyFrameDatabase, ReturnsTheRightKeyFrameAndHonoursOptions)
{
	std::mt19937_64 rng(6);
	KeyFrameDatabase db;
	const std::vector<BowVector> stored = addRandomKeyFrames(db, rng, 50, 0, 2000, 80);
	// The query: keyframe 17's vector with perturbed weights and 20 % of words replaced.
	BowVector q = stored[17];
	std::uniform_real_distribution<double> jitter(0.8, 1.2);
	for (auto& e : q) e.weight *= jitter(rng);
	for (std::size_t i = 0; i < q.size(); i += 5) q[i].word = static_cast<WordId>(1999 - i);
	canonicalise(q);
	normaliseL1(q);

	auto res = db.query(q);
	ASSERT_FALSE(res.empty());
	EXPECT_EQ(res[0].id, 17u);
	EXPECT_GT(res[0].score, 0.5);
	EXPECT_LE(res.size(), 10u);

	DatabaseQuery ex;
	ex.exclude = {17};
	res = db.query(q, ex);
	for (const auto& c : res) EXPECT_NE(c.id, 17u);

	// Reference-score normalisation: only candidates scoring at least the reference survive.
	DatabaseQuery ref;
	ref.minCommonWordsRatio = 0;
	ref.referenceScore = 0.3;
	res = db.query(q, ref);
	ASSERT_EQ(res.size(), 1u);
	EXPECT_EQ(res[0].id, 17u);

	EXPECT_TRUE(db.erase(17));
	EXPECT_FALSE(db.erase(17));
	EXPECT_FALSE(db.contains(17));
	EXPECT_EQ(db.size(), 49u);
	res = db.query(q);
	for (const auto& c : res) EXPECT_NE(c.id, 17u);
	// A re-added keyframe reuses the freed slot and is found again.
	db.add(99, stored[17]);
	res = db.query(q);
	ASSERT_FALSE(res.empty());
	EXPECT_EQ(res[0].id, 99u);
	EXPECT_THROW(db.bow(17), std::out_of_range);
}
