/** \file OptionFields_unittest.cpp
 * The table-driven option fields: strict reading, rules, writing with descriptions and a
 * write/read round trip.
 */
#include <gtest/gtest.h>
#include <keygrid/core/OptionFields.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "TestChecks.h"

using namespace keygrid;
using keygrid::test::errorOf;

namespace
{
/** A struct of every field type, with a custom (list) field. */
struct Options
{
	bool enabled{true};
	int count{10};
	std::uint64_t seed{12345};
	float radius{4.5f};
	double ratio{0.25};
	std::string type{"orb"};
	std::vector<double> radii{1.0, 2.0};

	core::OptionFields fields()
	{
		core::OptionFields f;
		f.add("enabled", enabled, "use it");
		f.add("count", count, "keypoints per frame", core::OptionRule::inRange(1, 100));
		f.add("seed", seed, "random seed");
		f.add("radius", radius, "search radius [px]", core::OptionRule::positive());
		f.add("ratio", ratio, "share of the map", core::OptionRule::aboveUpTo(0, 1));
		f.add("type", type, "orb | sift", core::OptionRule::oneOf({"orb", "sift"}));
		f.addCustom(
			"radii",
			{[this](const std::string& t) {
				 std::istringstream is(t);
				 radii.clear();
				 for (double x; is >> x;) radii.push_back(x);
				 if (!is.eof()) throw std::invalid_argument("not a list of numbers");
			 },
			 [this] {
				 std::ostringstream os;
				 for (std::size_t i = 0; i < radii.size(); i++) os << (i ? " " : "") << radii[i];
				 return os.str();
			 }},
			"shell radii [m]");
		return f;
	}
};

Options readFrom(const std::string& ini)
{
	Options o;
	o.fields().read(mrpt::config::CConfigFileMemory(ini), "opts");
	return o;
}
}  // namespace

TEST(OptionFields, ReadsValidValuesAndKeepsMissingOnes)
{
	const Options o = readFrom("[opts]\ncount = 42\nradius = 2.5\ntype = sift\nradii = 0.5 1 3\nenabled = false\n");
	EXPECT_EQ(o.count, 42);
	EXPECT_FLOAT_EQ(o.radius, 2.5f);
	EXPECT_EQ(o.type, "sift");
	EXPECT_EQ(o.radii, (std::vector<double>{0.5, 1.0, 3.0}));
	EXPECT_FALSE(o.enabled);
	EXPECT_EQ(o.seed, 12345u);
	EXPECT_DOUBLE_EQ(o.ratio, 0.25);
}

TEST(OptionFields, StrictReadRefusesMalformedValuesNamingSectionKeyAndValue)
{
	for (const char* bad : {"count = 12abc", "count = 1e3", "ratio = nan", "ratio = inf", "radius = 1e40", "enabled = maybe", "seed = -1", "radii = 1 x"})
	{
		const std::string line(bad);
		const std::string key = line.substr(0, line.find(' '));
		const std::string value = line.substr(line.find('=') + 2);
		const std::string e = errorOf([&] { readFrom("[opts]\n" + line + "\n"); });
		EXPECT_NE(e.find("[opts] " + key), std::string::npos) << bad << " -> " << e;
		EXPECT_NE(e.find(value.substr(0, 2)), std::string::npos) << bad << " -> " << e;
	}
}

TEST(OptionFields, ValidateNamesSectionKeyValueAndRule)
{
	EXPECT_EQ(errorOf([] { readFrom("[opts]\ncount = 101\n").fields().validate("opts"); }), "[opts] count = 101 (must be in [1, 100])");
	EXPECT_EQ(errorOf([] { readFrom("[opts]\nratio = 0\n").fields().validate("opts"); }), "[opts] ratio = 0 (must be in (0, 1])");
	EXPECT_EQ(errorOf([] { readFrom("[opts]\nradius = -0.5\n").fields().validate("opts"); }), "[opts] radius = -0.5 (must be > 0)");
	EXPECT_EQ(errorOf([] { readFrom("[opts]\ntype = surf\n").fields().validate("opts"); }), "[opts] type = 'surf' (must be one of orb, sift)");
	EXPECT_EQ(errorOf([] { readFrom("[opts]\nratio = 1\ncount = 100\n").fields().validate("opts"); }), "");
}

TEST(OptionFields, WriteThenReadGivesTheSameValues)
{
	Options a;
	a.enabled = false;
	a.count = 77;
	a.seed = 987654321012ULL;
	a.radius = 0.1f;
	a.ratio = 0.3;
	a.type = "sift";
	a.radii = {0.3, 1.7};
	mrpt::config::CConfigFileMemory mem;
	a.fields().write(mem, "opts");
	// Read back from the text, as a file would be (in memory, MRPT keeps the padding in the keys).
	std::string text;
	mem.getContent(text);
	Options b;
	b.fields().read(mrpt::config::CConfigFileMemory(text), "opts");
	EXPECT_EQ(b.enabled, a.enabled);
	EXPECT_EQ(b.count, a.count);
	EXPECT_EQ(b.seed, a.seed);
	EXPECT_EQ(b.radius, a.radius);
	EXPECT_EQ(b.ratio, a.ratio);
	EXPECT_EQ(b.type, a.type);
	EXPECT_EQ(b.radii, a.radii);
	// The description is the written comment.
	EXPECT_NE(text.find("// search radius [px]"), std::string::npos) << text;
}

namespace
{
/** One double and one float, written and read back through their table. */
struct Numbers
{
	double d{0};
	float x{0};

	core::OptionFields fields()
	{
		core::OptionFields f;
		f.add("d", d, "a double");
		f.add("x", x, "a float");
		return f;
	}
};

/** `n` written into an INI text, and that text. */
std::string writtenIni(Numbers n)
{
	mrpt::config::CConfigFileMemory mem;
	n.fields().write(mem, "n");
	std::string text;
	mem.getContent(text);
	return text;
}

Numbers readBack(Numbers n)
{
	Numbers back;
	back.d = -7;
	back.x = -7;
	back.fields().read(mrpt::config::CConfigFileMemory(writtenIni(n)), "n");
	return back;
}

template <typename T>
std::uint64_t bits(T v)
{
	std::uint64_t b = 0;
	std::memcpy(&b, &v, sizeof(v));
	return b;
}

/** The value text of key `key` in an INI text (without padding and comment). */
std::string valueIn(const std::string& ini, const std::string& key)
{
	return mrpt::config::CConfigFileMemory(ini).read_string("n", key, "?");
}

/** What MRPT's own write() makes of a number. */
template <typename T>
std::string mrptText(T v)
{
	mrpt::config::CConfigFileMemory mem;
	mem.write("n", "v", v);
	return mem.read_string("n", "v", "?");
}
}  // namespace

// MRPT's write() keeps 6 decimals ("%f") or 7 significant digits ("%e"): 2/3 would read back as
// 0.666667. The table writes floats and doubles so that they read back bit for bit.
TEST(OptionFields, WrittenNumbersReadBackBitForBit)
{
	const std::vector<double> doubles{
		0.1, 1e-9, 123456789.123, 2.0 / 3.0, -1.0 / 3.0, 0.000123456789, 67108864.0, 0.05, 1e300, 4.9e-324, 0.0, -0.0, 12345.678901234567, 123456789.0};
	const std::vector<float> floats{0.1f, 1e-9f, 123456.789f, 2.0f / 3.0f, 0.000123456f, 3.4e38f, 1e-40f, 0.85f, 0.0f};
	for (std::size_t i = 0; i < std::max(doubles.size(), floats.size()); i++)
	{
		Numbers n;
		n.d = doubles[i % doubles.size()];
		n.x = floats[i % floats.size()];
		const Numbers back = readBack(n);
		EXPECT_EQ(bits(back.d), bits(n.d)) << valueIn(writtenIni(n), "d") << " for " << n.d;
		EXPECT_EQ(bits(back.x), bits(n.x)) << valueIn(writtenIni(n), "x") << " for " << n.x;
	}
}

// Values that MRPT's text already keeps exactly are written as MRPT writes them; the others in
// their shortest exact text.
TEST(OptionFields, WrittenNumbersKeepMrptTextWhereItIsExact)
{
	for (const double v : {0.05, 0.25, 1e-9, 3.0, 0.0, 2.5e7})
	{
		Numbers n;
		n.d = v;
		n.x = static_cast<float>(v);
		const std::string ini = writtenIni(n);
		EXPECT_EQ(valueIn(ini, "d"), mrptText(v));
		EXPECT_EQ(valueIn(ini, "x"), mrptText(static_cast<float>(v)));
	}
	Numbers n;
	n.d = 2.0 / 3.0;
	n.x = 123456.789f;
	EXPECT_EQ(valueIn(writtenIni(n), "d"), "0.6666666666666666");
	EXPECT_EQ(valueIn(writtenIni(n), "x"), "123456.79");
	n.d = 123456789.123;
	n.x = 1e-9f;
	EXPECT_EQ(valueIn(writtenIni(n), "d"), "123456789.123");
	EXPECT_EQ(valueIn(writtenIni(n), "x"), "1.000000e-09");
	// A whole number keeps a decimal point, as MRPT's "%f" and "%e" do (a written default tells
	// number keys from integer keys).
	n.d = 123456789.0;
	n.x = -16777215.0f;
	EXPECT_EQ(valueIn(writtenIni(n), "d"), "123456789.0");
	EXPECT_EQ(valueIn(writtenIni(n), "x"), "-16777215.0");
}

TEST(OptionFields, EveryFieldIsDescribed)
{
	Options o;
	const core::OptionFields table = o.fields();
	for (const auto& f : table.fields()) EXPECT_FALSE(f.description.empty()) << f.key;
}
