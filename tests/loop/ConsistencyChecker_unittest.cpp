#include <gtest/gtest.h>
#include <keygrid/loop/ConsistencyChecker.h>

using namespace keygrid::loop;

TEST(ConsistencyChecker, AcceptsOnlyAfterConsecutiveOverlappingGroups)
{
	ConsistencyChecker cc(3);
	// A real revisit: candidates 10, 11, 12 for three consecutive queries, their covisibility
	// groups overlapping ({9,10,11}, {10,11,12}, {11,12,13}).
	EXPECT_TRUE(cc.check({{10, {9, 11}}}).empty());
	EXPECT_TRUE(cc.check({{11, {10, 12}}}).empty());
	const auto acc = cc.check({{12, {11, 13}}});
	ASSERT_EQ(acc.size(), 1u);
	EXPECT_EQ(acc[0], 12u);
	// The chain continues.
	EXPECT_EQ(cc.check({{13, {12, 14}}}).size(), 1u);
}

TEST(ConsistencyChecker, SpuriousOrInterruptedCandidatesAreRejected)
{
	ConsistencyChecker cc(3);
	// Candidates jumping between unrelated places never chain.
	EXPECT_TRUE(cc.check({{10, {9, 11}}}).empty());
	EXPECT_TRUE(cc.check({{50, {49, 51}}}).empty());
	EXPECT_TRUE(cc.check({{90, {89, 91}}}).empty());
	// A query without candidates breaks every chain.
	EXPECT_TRUE(cc.check({{10, {9, 11}}}).empty());
	EXPECT_TRUE(cc.check({{11, {10, 12}}}).empty());
	EXPECT_TRUE(cc.check({}).empty());
	EXPECT_EQ(cc.activeGroups(), 0u);
	EXPECT_TRUE(cc.check({{12, {11, 13}}}).empty());
	// Two candidates per query: only the consistent one is accepted.
	EXPECT_TRUE(cc.check({{13, {12, 14}}, {70, {69}}}).empty());
	const auto acc = cc.check({{200, {201}}, {14, {13, 15}}});
	ASSERT_EQ(acc.size(), 1u);
	EXPECT_EQ(acc[0], 14u);
	cc.reset();
	EXPECT_TRUE(cc.check({{15, {14}}}).empty());
	EXPECT_THROW(ConsistencyChecker(0), std::invalid_argument);
	ConsistencyChecker one(1);
	EXPECT_EQ(one.check({{5, {}}}).size(), 1u);
}
