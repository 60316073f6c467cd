#include <keygrid/core/CommandLine.h>

#include "TestData.h"

using keygrid::core::CommandLine;
using keygrid::core::CommandLineError;

namespace
{
CommandLine make()
{
	CommandLine cl("tool", "does things");
	cl.option("input", "PATH", "input", true).option("rate", "HZ", "rate", false, "30").flag("quiet", "q");
	return cl;
}
}  // namespace

TEST(CommandLine, ParsesValuesFlagsAndDefaults)
{
	auto cl = make();
	const char* argv[] = {"tool", "--input", "a.txt", "--quiet", "--rate=12.5"};
	ASSERT_TRUE(cl.parse(5, argv));
	EXPECT_EQ(cl.get("input"), "a.txt");
	EXPECT_TRUE(cl.flagSet("quiet"));
	EXPECT_DOUBLE_EQ(cl.getDouble("rate"), 12.5);
	auto cl2 = make();
	const char* argv2[] = {"tool", "--input", "b"};
	ASSERT_TRUE(cl2.parse(3, argv2));
	EXPECT_DOUBLE_EQ(cl2.getDouble("rate"), 30.0);
	EXPECT_FALSE(cl2.flagSet("quiet"));
}

TEST(CommandLine, OneLineErrorsNameTheOption)
{
	auto expectError = [](std::vector<const char*> args, const std::string& needle) {
		auto cl = make();
		try
		{
			cl.parse(static_cast<int>(args.size()), args.data());
			ADD_FAILURE() << "no error for " << needle;
		}
		catch (const CommandLineError& e)
		{
			EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
			EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
		}
	};
	expectError({"tool"}, "missing --input");
	expectError({"tool", "--input", "x", "--bogus"}, "unknown option --bogus");
	expectError({"tool", "--input"}, "--input needs a value");
	expectError({"tool", "--input", "x", "stray"}, "unexpected argument 'stray'");
	auto cl = make();
	const char* argv[] = {"tool", "--input", "x", "--rate", "fast"};
	ASSERT_TRUE(cl.parse(5, argv));
	EXPECT_THROW(cl.getDouble("rate"), CommandLineError);
}

TEST(CommandLine, HelpReturnsFalseAndListsOptions)
{
	auto cl = make();
	const char* argv[] = {"tool", "--help"};
	testing::internal::CaptureStdout();
	EXPECT_FALSE(cl.parse(2, argv));
	const std::string out = testing::internal::GetCapturedStdout();
	EXPECT_NE(out.find("--input PATH"), std::string::npos);
	EXPECT_NE(out.find("(default: 30)"), std::string::npos);
}
