// keygrid-eval run as a user would, including the acceptance checks.
#include <keygrid/core/TumTrajectory.h>

#include "TestData.h"

#include <fstream>
#include <random>
#include <regex>

using keygrid::test::runCommand;

TEST(EvalTool, GroundTruthAgainstItselfIsZeroAndNoiseRmseIsRecovered)
{
	const std::string dir = keygrid::test::scratchDir("eval_tool");
	keygrid::core::Trajectory gt, est;
	std::mt19937 g(7);
	std::normal_distribution<double> nd(0, 0.01 / std::sqrt(3.0));
	const mrpt::poses::CPose3D T(0.5, 2.0, -1.0, 0.8, 0.1, -0.2);
	double sq = 0;
	for (int i = 0; i < 1500; i++)
	{
		const double t = 1305031102.0 + i / 30.0;
		mrpt::poses::CPose3D p(std::sin(0.1 * t), std::cos(0.13 * t), 0.2 * std::sin(0.3 * t), 0.2 * t, 0.1, -0.1);
		gt.push_back({t, p});
		const double ex = nd(g), ey = nd(g), ez = nd(g);
		sq += ex * ex + ey * ey + ez * ez;
		p.x_incr(ex);
		p.y_incr(ey);
		p.z_incr(ez);
		est.push_back({t, T + p});
	}
	keygrid::core::writeTumTrajectory(dir + "/gt.txt", gt);
	keygrid::core::writeTumTrajectory(dir + "/est.txt", est);
	const std::string tool = keygrid::test::toolPath("keygrid-eval");
	std::string out;
	ASSERT_EQ(runCommand(tool + " --gt " + dir + "/gt.txt --est " + dir + "/gt.txt --json " + dir + "/self.json", &out), 0) << out;
	const std::string self = keygrid::test::readTextFile(dir + "/self.json");
	EXPECT_NEAR(keygrid::test::jsonNumber(self, "ate_rmse_m"), 0.0, 1e-9);
	EXPECT_EQ(keygrid::test::jsonNumber(self, "matched"), 1500);
	EXPECT_NEAR(keygrid::test::jsonNumber(self, "rpe_trans_m_per_s"), 0.0, 1e-9);
	EXPECT_NE(out.find("ATE rmse 0.000000 m"), std::string::npos) << out;

	ASSERT_EQ(runCommand(tool + " --gt " + dir + "/gt.txt --est " + dir + "/est.txt --json " + dir + "/n.json", &out), 0) << out;
	EXPECT_NEAR(keygrid::test::jsonNumber(keygrid::test::readTextFile(dir + "/n.json"), "ate_rmse_m"), std::sqrt(sq / 1500), 1e-4);
}

TEST(EvalTool, BadInputsGiveOneLineReasons)
{
	const std::string dir = keygrid::test::scratchDir("eval_bad");
	std::ofstream(dir + "/bad.txt") << "# x\n1 2 3\n";
	std::ofstream(dir + "/ok.txt") << "1 0 0 0 0 0 0 1\n2 1 0 0 0 0 0 1\n3 1 1 0 0 0 0 1\n";
	std::ofstream(dir + "/far.txt") << "101 0 0 0 0 0 0 1\n102 1 0 0 0 0 0 1\n103 1 1 0 0 0 0 1\n";
	const std::string tool = keygrid::test::toolPath("keygrid-eval");
	std::string out;
	EXPECT_EQ(runCommand(tool + " --gt " + dir + "/ok.txt --est " + dir + "/bad.txt", &out), 1);
	EXPECT_NE(out.find("bad.txt:2: expected 8 fields"), std::string::npos) << out;
	EXPECT_EQ(runCommand(tool + " --gt " + dir + "/ok.txt --est " + dir + "/far.txt", &out), 1);
	EXPECT_NE(out.find("only 0 estimated poses"), std::string::npos) << out;
	EXPECT_EQ(runCommand(tool + " --gt " + dir + "/ok.txt", &out), 2);
	EXPECT_NE(out.find("missing --est"), std::string::npos) << out;
	EXPECT_EQ(runCommand(tool + " --gt " + dir + "/missing.txt --est " + dir + "/ok.txt", &out), 1);
	EXPECT_NE(out.find("cannot open"), std::string::npos) << out;
	EXPECT_EQ(runCommand(tool + " --gt " + dir + "/ok.txt --est " + dir + "/ok.txt --delta -3", &out), 2) << out;
}
