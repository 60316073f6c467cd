/** \file ConfigReading_unittest.cpp
 * The strict INI readers: whole numbers in a range, booleans true/false/1/0, finite numbers;
 * every refusal names section, key and value.
 */
#include <gtest/gtest.h>
#include <keygrid/core/ConfigReading.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <stdexcept>
#include <string>

#include "TestChecks.h"

using namespace keygrid;
using keygrid::test::errorOf;

TEST(ConfigReading, IntegersAreWholeNumbersInTheirRange)
{
	mrpt::config::CConfigFileMemory c;
	c.write("s", "ok", std::string(" 42 "));
	c.write("s", "neg", std::string("-7"));
	EXPECT_EQ(core::readInteger(c, "s", "ok", 1, 0, 100), 42);
	EXPECT_EQ(core::readInteger(c, "s", "neg", 1, -10, 10), -7);
	EXPECT_EQ(core::readInteger(c, "s", "missing", 5, 0, 10), 5);
	for (const std::string bad : {"1000abc", "40.0.0", "1e3", "forty", "4.5", "-", "12345678901234567890"})
	{
		c.write("s", "k", bad);
		const auto e = errorOf([&] { core::readInteger(c, "s", "k", 1, 0, 1000000); });
		EXPECT_NE(e.find("[s] k = '" + bad + "' is not a whole number in [0, 1000000]"), std::string::npos) << bad << ": " << e;
	}
	c.write("s", "k", std::string("2.5"));
	EXPECT_NE(errorOf([&] { core::readWholeNumber(c, "s", "k", 1); }).find("[s] k = '2.5' is not a whole number"), std::string::npos);
	c.write("s", "k", std::string("-12"));
	EXPECT_EQ(core::readWholeNumber(c, "s", "k", 1), -12);
	c.write("s", "k", std::string("1001"));
	EXPECT_NE(errorOf([&] { core::readInteger(c, "s", "k", 1, 0, 1000); }).find("[s] k = 1001 is out of range [0, 1000]"), std::string::npos);
}

TEST(ConfigReading, BooleansAreTrueFalseOneOrZero)
{
	mrpt::config::CConfigFileMemory c;
	const std::pair<const char*, bool> good[] = {{"true", true}, {"TRUE", true}, {"1", true}, {"false", false}, {"False", false}, {" 0 ", false}};
	for (const auto& [text, value] : good)
	{
		c.write("s", "b", std::string(text));
		EXPECT_EQ(core::readBoolean(c, "s", "b", !value), value) << text;
	}
	EXPECT_TRUE(core::readBoolean(c, "s", "missing", true));
	for (const std::string bad : {"maybe", "yes!", "2", "on-ish"})
	{
		c.write("s", "b", bad);
		EXPECT_NE(errorOf([&] { core::readBoolean(c, "s", "b", false); }).find("[s] b = '" + bad + "' is not a boolean"), std::string::npos) << bad;
	}
}

TEST(ConfigReading, FiniteNumbersRefuseTextAndInfinity)
{
	mrpt::config::CConfigFileMemory c;
	c.write("s", "x", std::string("0.25"));
	EXPECT_DOUBLE_EQ(core::readFiniteNumber(c, "s", "x", 1.0), 0.25);
	for (const std::string bad : {"inf", "nan", "forty", "1.5m"})
	{
		c.write("s", "x", bad);
		EXPECT_NE(errorOf([&] { core::readFiniteNumber(c, "s", "x", 1.0); }).find("is not a finite number"), std::string::npos) << bad;
	}
}
