#include <keygrid/core/TumTrajectory.h>

#include "TestData.h"

#include <fstream>

using namespace keygrid::core;

namespace
{
std::string writeText(const std::string& name, const std::string& text)
{
	const std::string p = keygrid::test::scratchDir("tumtraj_" + name) + "/t.txt";
	std::ofstream(p) << text;
	return p;
}
}  // namespace

TEST(TumTrajectory, ParsesHeadersCommentsBlankLinesAndCommas)
{
	const auto p = writeText(
		"ok",
		"# ground truth trajectory\n"
		"# file: 'x.bag'\n"
		"# timestamp tx ty tz qx qy qz qw\n"
		"\n"
		"2.0 1 2 3 0 0 0 1   # trailing comment\n"
		"1.0,0.5,0,0,0,0,0.7071067811865476,0.7071067811865476\r\n");
	const auto t = readTumTrajectory(p);
	ASSERT_EQ(t.size(), 2u);
	EXPECT_DOUBLE_EQ(t[0].t, 1.0);  // sorted by time
	EXPECT_NEAR(t[0].T_world_cam.x(), 0.5, 1e-15);
	EXPECT_NEAR(t[0].T_world_cam.yaw(), M_PI / 2, 1e-12);
	EXPECT_DOUBLE_EQ(t[1].T_world_cam.z(), 3.0);
}

TEST(TumTrajectory, BadLinesThrowWithFileAndLineOrAreSkipped)
{
	const auto p = writeText(
		"bad",
		"# header\n"
		"1.0 0 0 0 0 0 0 1\n"
		"2.0 0 0 0 0 0 1\n"            // 7 fields
		"3.0 0 0 x 0 0 0 1\n"          // not a number
		"4.0 0 0 0 0 0 0 2\n"          // |q| = 2
		"5.0 0 0 0 0 0 0 nan\n"        // nan
		"6.0 0 0 0 0 0 0 1.0000001\n"  // tiny drift: renormalised, accepted
	);
	try
	{
		readTumTrajectory(p);
		FAIL() << "no exception";
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_NE(std::string(e.what()).find(p + ":3:"), std::string::npos) << e.what();
	}
	TrajectoryReadOptions o;
	o.skipBadLines = true;
	std::vector<TextLineIssue> issues;
	const auto t = readTumTrajectory(p, o, &issues);
	ASSERT_EQ(t.size(), 2u);
	EXPECT_DOUBLE_EQ(t[1].t, 6.0);
	ASSERT_EQ(issues.size(), 4u);
	EXPECT_EQ(issues[0].line, 3u);
	EXPECT_EQ(issues[1].line, 4u);
	EXPECT_EQ(issues[2].line, 5u);
	EXPECT_EQ(issues[3].line, 6u);
}

TEST(TumTrajectory, ARepeatedTimestampIsNamedOnTheLineThatRepeatsIt)
{
	const auto p = writeText(
		"repeat",
		"# header\n"
		"2.0 0 0 0 0 0 0 1\n"
		"1.0 0 0 0 0 0 0 1\n"
		"2.0 1 0 0 0 0 0 1\n"  // line 4 repeats line 2's stamp
		"3.0 0 0 0 0 0 0 1\n");
	try
	{
		readTumTrajectory(p);
		FAIL() << "no exception";
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_NE(std::string(e.what()).find(p + ":4: repeated timestamp 2.000000 (first on line 2)"), std::string::npos) << e.what();
	}
	TrajectoryReadOptions o;
	o.skipBadLines = true;
	std::vector<TextLineIssue> issues;
	const auto t = readTumTrajectory(p, o, &issues);
	ASSERT_EQ(t.size(), 3u);
	EXPECT_DOUBLE_EQ(t[1].T_world_cam.x(), 0.0) << "the first of the repeated poses is kept";
	ASSERT_EQ(issues.size(), 1u);
	EXPECT_EQ(issues[0].line, 4u);
}

TEST(TumTrajectory, WriteReadRoundTrip)
{
	Trajectory in;
	for (int i = 0; i < 20; i++)
		in.push_back({1305031453.123456 + i * 0.033, mrpt::poses::CPose3D(0.1 * i, -0.2 * i, 1.0, 0.05 * i, -0.03 * i, 0.02 * i)});
	const std::string p = keygrid::test::scratchDir("tumtraj_rt") + "/traj.txt";
	writeTumTrajectory(p, in);
	const auto out = readTumTrajectory(p);
	ASSERT_EQ(out.size(), in.size());
	for (std::size_t i = 0; i < in.size(); i++)
	{
		EXPECT_NEAR(out[i].t, in[i].t, 1e-6);
		EXPECT_NEAR((out[i].T_world_cam.asVectorVal() - in[i].T_world_cam.asVectorVal()).norm(), 0.0, 1e-8);
	}
	EXPECT_THROW(readTumTrajectory(p + ".missing"), std::runtime_error);
}
