#include <keygrid/core/ConfigReading.h>
#include <keygrid/core/OptionFields.h>
#include <mrpt/config/CConfigFileBase.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <type_traits>

namespace keygrid::core
{
namespace
{
constexpr double kInf = std::numeric_limits<double>::infinity();

/** Whole numbers without exponent, others in the shortest "%g" text that reads back to the same
 * value (of the field's precision). */
template <typename T>
std::string shortestText(T v)
{
	char b[64];
	if (v == std::floor(v) && std::abs(v) < 1e15)
	{
		std::snprintf(b, sizeof(b), "%.0f", static_cast<double>(v));
		return b;
	}
	for (int p = 1; p <= 17; p++)
	{
		std::snprintf(b, sizeof(b), "%.*g", p, static_cast<double>(v));
		if (static_cast<T>(std::strtod(b, nullptr)) == v) break;
	}
	return b;
}

/** What MRPT's CConfigFileBase::write() prints for a float or double: "%f" (6 decimals) for
 * 1e-4 < |v| < 1e4 and for 0, "%e" (7 significant digits) otherwise. */
template <typename T>
std::string mrptText(T v)
{
	char b[64];
	const bool fixed = (std::abs(v) > static_cast<T>(1e-4) && std::abs(v) < static_cast<T>(1e4)) || v == 0;
	std::snprintf(b, sizeof(b), fixed ? "%f" : "%e", static_cast<double>(v));
	return b;
}

/** The text written for a number field: MRPT's own form ("0.050000", "1.000000e-09") when it
 * reads back as the same value, so files look as MRPT's maps write them; otherwise (2/3,
 * 123456789.123, 0.000123456) the shortest text that does, as MRPT's form would change the value
 * on a save and load. Either has a decimal point or an exponent, as MRPT's has: written
 * defaults tell number keys from integer keys (slam::SlamConfig::checkKnownKeys). */
template <typename T>
std::string writtenText(T v)
{
	std::string text = mrptText(v);
	if (static_cast<T>(std::strtod(text.c_str(), nullptr)) == v) return text;
	text = shortestText(v);
	if (text.find_first_of(".e") == std::string::npos) text += ".0";
	return text;
}

/** The largest whole number readWholeNumber() parses (18 digits). */
constexpr long long kMaxWhole = 999999999999999999LL;

template <typename T>
void readInto(const mrpt::config::CConfigFileBase& c, const std::string& s, const std::string& k, T& v)
{
	if constexpr (std::is_same_v<T, bool>)
		v = readBoolean(c, s, k, v);
	else if constexpr (std::is_same_v<T, std::string>)
		v = c.read_string(s, k, v);
	else if constexpr (std::is_floating_point_v<T>)
	{
		const double x = readFiniteNumber(c, s, k, v);
		if (!std::isfinite(static_cast<T>(x)))
			throw std::invalid_argument("[" + s + "] " + k + " = " + shortestText(x) + " is out of the range of a float");
		v = static_cast<T>(x);
	}
	else
	{
		// The rule bounds the value; the type's range is only checked here.
		const long long lo = std::is_signed_v<T> ? static_cast<long long>(std::numeric_limits<T>::min()) : 0;
		const long long hi = static_cast<long long>(std::min<unsigned long long>(std::numeric_limits<T>::max(), kMaxWhole));
		const long long x = readWholeNumber(c, s, k, static_cast<long long>(v));
		if (x < lo || x > hi)
			throw std::invalid_argument("[" + s + "] " + k + " = " + std::to_string(x) + " is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
		v = static_cast<T>(x);
	}
}
}  // namespace

OptionRule OptionRule::any() { return {}; }

OptionRule OptionRule::positive() { return between(0, kInf); }

OptionRule OptionRule::atLeast(double min) { return inRange(min, kInf); }

OptionRule OptionRule::inRange(double lo, double hi)
{
	OptionRule r;
	r.m_kind = Kind::Interval;
	r.m_lo = lo;
	r.m_hi = hi;
	return r;
}

OptionRule OptionRule::aboveUpTo(double lo, double hi)
{
	OptionRule r = inRange(lo, hi);
	r.m_loOpen = true;
	return r;
}

OptionRule OptionRule::fromBelow(double lo, double hi)
{
	OptionRule r = inRange(lo, hi);
	r.m_hiOpen = true;
	return r;
}

OptionRule OptionRule::between(double lo, double hi)
{
	OptionRule r = inRange(lo, hi);
	r.m_loOpen = r.m_hiOpen = true;
	return r;
}

OptionRule OptionRule::oneOf(std::vector<std::string> words)
{
	OptionRule r;
	r.m_kind = Kind::Words;
	r.m_words = std::move(words);
	return r;
}

OptionRule OptionRule::nonEmpty()
{
	OptionRule r;
	r.m_kind = Kind::NonEmpty;
	return r;
}

bool OptionRule::accepts(double v) const
{
	if (m_kind != Kind::Interval) return true;
	const bool aboveLo = m_loOpen ? v > m_lo : v >= m_lo;
	const bool belowHi = m_hiOpen ? v < m_hi : v <= m_hi;
	return aboveLo && belowHi;
}

bool OptionRule::accepts(const std::string& v) const
{
	if (m_kind == Kind::NonEmpty) return !v.empty();
	if (m_kind != Kind::Words) return true;
	for (const auto& w : m_words)
		if (v == w) return true;
	return false;
}

std::string shortestNumberText(double v) { return shortestText(v); }

std::string OptionRule::text() const
{
	switch (m_kind)
	{
		case Kind::Any: return "any value";
		case Kind::NonEmpty: return "not empty";
		case Kind::Words:
		{
			std::string t = "one of";
			for (std::size_t i = 0; i < m_words.size(); i++) t += (i ? ", " : " ") + m_words[i];
			return t;
		}
		case Kind::Interval: break;
	}
	if (m_hi == kInf) return (m_loOpen ? "> " : ">= ") + shortestText(m_lo);
	if (m_lo == -kInf) return (m_hiOpen ? "< " : "<= ") + shortestText(m_hi);
	return std::string("in ") + (m_loOpen ? "(" : "[") + shortestText(m_lo) + ", " + shortestText(m_hi) + (m_hiOpen ? ")" : "]");
}

std::string OptionField::valueText() const
{
	return std::visit(
		[](const auto& m) -> std::string {
			using P = std::decay_t<decltype(m)>;
			if constexpr (std::is_same_v<P, CustomOptionValue>)
				return "'" + m.format() + "'";
			else
			{
				using T = std::remove_pointer_t<P>;
				if constexpr (std::is_same_v<T, bool>)
					return *m ? "true" : "false";
				else if constexpr (std::is_same_v<T, std::string>)
					return "'" + *m + "'";
				else if constexpr (std::is_floating_point_v<T>)
					return shortestText(*m);
				else
					return std::to_string(*m);
			}
		},
		member);
}

bool OptionField::accepted() const
{
	return std::visit(
		[&](const auto& m) {
			using P = std::decay_t<decltype(m)>;
			if constexpr (std::is_same_v<P, CustomOptionValue>)
				return rule.accepts(m.format());
			else if constexpr (std::is_same_v<P, std::string*>)
				return rule.accepts(*m);
			else
				return rule.accepts(static_cast<double>(*m));
		},
		member);
}

OptionFields::OptionFields(int nameWidth, int valueWidth) : m_nameWidth(nameWidth), m_valueWidth(valueWidth) {}

OptionFields& OptionFields::addCustom(const std::string& key, CustomOptionValue value, const std::string& description, OptionRule rule)
{
	m_fields.push_back({key, OptionField::Member(std::move(value)), description, std::move(rule)});
	return *this;
}

OptionFields& OptionFields::append(const OptionFields& other)
{
	m_fields.insert(m_fields.end(), other.m_fields.begin(), other.m_fields.end());
	return *this;
}

void OptionFields::read(const mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	for (const auto& f : m_fields)
		std::visit(
			[&](const auto& m) {
				using P = std::decay_t<decltype(m)>;
				if constexpr (std::is_same_v<P, CustomOptionValue>)
				{
					const std::string text = c.read_string(s, f.key, "", false);
					if (text.empty()) return;
					try
					{
						m.parse(text);
					}
					catch (const std::invalid_argument& e)
					{
						throw std::invalid_argument("[" + s + "] " + f.key + " = '" + text + "' (" + e.what() + ")");
					}
				}
				else
					readInto(c, s, f.key, *m);
			},
			f.member);
}

void OptionFields::write(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	for (const auto& f : m_fields)
		std::visit(
			[&](const auto& m) {
				using P = std::decay_t<decltype(m)>;
				if constexpr (std::is_same_v<P, CustomOptionValue>)
					c.write(s, f.key, m.format(), m_nameWidth, m_valueWidth, f.description);
				else if constexpr (std::is_floating_point_v<std::remove_pointer_t<P>>)
					c.write(s, f.key, writtenText(*m), m_nameWidth, m_valueWidth, f.description);
				else
					c.write(s, f.key, *m, m_nameWidth, m_valueWidth, f.description);
			},
			f.member);
}

void OptionFields::validate(const std::string& s) const
{
	for (const auto& f : m_fields)
		if (!f.accepted()) throw std::invalid_argument("[" + s + "] " + f.key + " = " + f.valueText() + " (must be " + f.rule.text() + ")");
}

}  // namespace keygrid::core
