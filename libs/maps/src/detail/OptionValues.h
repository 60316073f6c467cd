#pragma once
/** \file OptionValues.h
 * Private helpers of the map plugins' option tables (core::OptionFields): fields whose INI text
 * the options parse and format themselves (booleans as the maps have always read them, enums
 * as words, exact numbers, vectors).
 */
#include <keygrid/core/ConfigReading.h>
#include <keygrid/core/OptionFields.h>
#include <mrpt/math/TPoint3D.h>

#include <algorithm>
#include <cctype>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace keygrid::detail
{
/** < 0 */
inline core::OptionRule negative() { return core::OptionRule::between(-std::numeric_limits<double>::infinity(), 0); }

/** A boolean written true/false, read as true/false/yes/no/1/0 in any letter case: the map
 * plugins' sections always took MRPT's yes/no as well. */
inline core::CustomOptionValue flagValue(bool& flag)
{
	return {
		[&flag](const std::string& text) {
			std::string v = core::trimBlanks(text);
			std::transform(v.begin(), v.end(), v.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
			if (v == "true" || v == "yes" || v == "1") flag = true;
			else if (v == "false" || v == "no" || v == "0")
				flag = false;
			else
				throw std::invalid_argument("expected true, false, yes, no, 1 or 0");
		},
		[&flag] { return std::string(flag ? "true" : "false"); }};
}

/** Adds an enum field written as one of `words` (exact spelling); other text throws naming
 * the words. */
template <typename Enum>
void addWords(
	core::OptionFields& f, const std::string& key, Enum& value, const std::vector<std::pair<std::string, Enum>>& words,
	const std::string& description)
{
	std::vector<std::string> names;
	std::string expected;
	for (const auto& [name, v] : words)
	{
		expected += (names.empty() ? "expected '" : (names.size() + 1 == words.size() ? " or '" : ", '")) + name + "'";
		names.push_back(name);
	}
	f.addCustom(
		key,
		{[&value, words, expected](const std::string& text) {
			 for (const auto& [name, v] : words)
				 if (text == name)
				 {
					 value = v;
					 return;
				 }
			 throw std::invalid_argument(expected);
		 },
		 [&value, words] {
			 for (const auto& [name, v] : words)
				 if (v == value) return name;
			 return std::string("?");
		 }},
		description, core::OptionRule::oneOf(names));
}

/** A vector written "x y z" (three numbers, nothing else; each written exactly). */
inline core::CustomOptionValue vectorValue(mrpt::math::TVector3D& vec)
{
	return {
		[&vec](const std::string& text) {
			std::istringstream is(text);
			double x = 0, y = 0, z = 0;
			if (!(is >> x >> y >> z) || !(is >> std::ws).eof()) throw std::invalid_argument("expected three numbers \"x y z\"");
			vec = mrpt::math::TVector3D(x, y, z);
		},
		[&vec] {
			return core::shortestNumberText(vec.x) + " " + core::shortestNumberText(vec.y) + " " +
				core::shortestNumberText(vec.z);
		}};
}

}  // namespace keygrid::detail
