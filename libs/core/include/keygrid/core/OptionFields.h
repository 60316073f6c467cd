#pragma once
/** \file OptionFields.h
 * One table per options struct drives its INI reading, writing and checking: each field names
 * its INI key, the member it sets, a one-line description (with the unit) and the values it
 * accepts. Reading is strict (ConfigReading.h): "12abc", "nan" or "maybe" throw
 * std::invalid_argument naming [section], key and value. Writing puts the description as the
 * comment, which is also the field's row in doc/ini-reference.md; a float or double is written
 * so that reading it back gives the same value bit for bit. validate() throws
 * std::invalid_argument("[section] key = value (must be <rule>)") for the first field whose
 * value breaks its rule; checks that relate two fields stay with the struct, after these.
 *
 * A struct builds its table on itself:
 *
 *     core::OptionFields TrackerOptions::fields()
 *     {
 *         core::OptionFields f(34);
 *         f.add("min_inliers", minInliers, "inliers to call a frame tracked", core::OptionRule::positive());
 *         ...
 *     }
 *
 * The table points into the struct it was built on, so const members build it on a copy
 * (writeFields, validateFields).
 */
#include <cstdint>
#include <functional>
#include <string>
#include <variant>
#include <vector>

namespace mrpt::config
{
class CConfigFileBase;
}

namespace keygrid::core
{
/** The values a field accepts: any, an interval (each end open or closed, possibly
 * unbounded), or one of a list of words (text fields). */
class OptionRule
{
   public:
	/** Every value of the field's type. */
	static OptionRule any();
	/** > 0 */
	static OptionRule positive();
	/** >= min */
	static OptionRule atLeast(double min);
	/** In [lo, hi]. */
	static OptionRule inRange(double lo, double hi);
	/** In (lo, hi] (e.g. a share that must not be 0). */
	static OptionRule aboveUpTo(double lo, double hi);
	/** In [lo, hi) (e.g. a probability threshold that must stay below 1). */
	static OptionRule fromBelow(double lo, double hi);
	/** In (lo, hi). */
	static OptionRule between(double lo, double hi);
	/** One of these words (text fields). */
	static OptionRule oneOf(std::vector<std::string> words);
	/** Text that is not empty. */
	static OptionRule nonEmpty();

	bool accepts(double value) const;
	bool accepts(const std::string& value) const;
	/** What an accepted value is, completing "must be ...": "> 0", "in (0, 1]", "one of orb, sift". */
	std::string text() const;

   private:
	enum class Kind
	{
		Any,
		Interval,
		Words,
		NonEmpty
	};
	Kind m_kind{Kind::Any};
	double m_lo{0}, m_hi{0};
	bool m_loOpen{false}, m_hiOpen{false};
	std::vector<std::string> m_words;
};

/** A number in the shortest text that reads back as the same double: whole numbers without
 * exponent ("3"), others in the shortest "%g" form that round-trips ("0.1", "0.6666666666666666"). */
std::string shortestNumberText(double v);

/** A field whose INI text is parsed and formatted by the struct itself (lists, poses, enums):
 * `parse` throws std::invalid_argument with the reason ("expected x y z") when the text is not
 * a valid value, `format` gives the text written for the current value. */
struct CustomOptionValue
{
	std::function<void(const std::string&)> parse;
	std::function<std::string()> format;
};

/** One INI key of an options struct. */
struct OptionField
{
	using Member = std::variant<bool*, int*, std::uint32_t*, std::uint64_t*, float*, double*, std::string*, CustomOptionValue>;
	std::string key;
	Member member;
	std::string description;  //!< one line, with the unit
	OptionRule rule;

	/** The current value as text: numbers in their shortest exact form, text quoted. */
	std::string valueText() const;
	/** Whether `rule` accepts the current value. */
	bool accepted() const;
};

class OptionFields
{
   public:
	/** `nameWidth`, `valueWidth`: the padding of key and value in written INI lines. */
	explicit OptionFields(int nameWidth = 30, int valueWidth = 40);

	/** Adds a field; `T` is bool, int, uint32_t, uint64_t, float, double or std::string. */
	template <typename T>
	OptionFields& add(const std::string& key, T& member, const std::string& description, OptionRule rule = OptionRule::any())
	{
		m_fields.push_back({key, OptionField::Member(&member), description, std::move(rule)});
		return *this;
	}
	/** Adds a field whose text the struct parses and formats itself. */
	OptionFields& addCustom(
		const std::string& key, CustomOptionValue value, const std::string& description,
		OptionRule rule = OptionRule::any());
	/** Appends the fields of a nested struct's table (same section). */
	OptionFields& append(const OptionFields& other);

	/** Sets every field present in `section`; a missing key keeps the member's value. Throws
	 * std::invalid_argument naming [section], key and value for text that is not a value of the
	 * field's type (whole numbers for integers, finite numbers, true/false/1/0). Rules are
	 * validate()'s to check. */
	void read(const mrpt::config::CConfigFileBase& cfg, const std::string& section) const;
	/** Writes every field with its description as comment, in table order. Numbers are written
	 * as MRPT's write() prints them ("0.050000") when that text reads back as the same value,
	 * else in their shortest text that does ("0.6666666666666666"). */
	void write(mrpt::config::CConfigFileBase& cfg, const std::string& section) const;
	/** Throws std::invalid_argument("[section] key = value (must be <rule>)") for the first field
	 * whose value its rule refuses. */
	void validate(const std::string& section) const;

	const std::vector<OptionField>& fields() const { return m_fields; }

   private:
	std::vector<OptionField> m_fields;
	int m_nameWidth, m_valueWidth;
};

/** Writes a const options struct through the table of a copy of it. */
template <class Options>
void writeFields(const Options& o, mrpt::config::CConfigFileBase& cfg, const std::string& section)
{
	Options copy(o);
	copy.fields().write(cfg, section);
}

/** OptionFields::validate() of a const options struct, through the table of a copy of it. */
template <class Options>
void validateFields(const Options& o, const std::string& section)
{
	Options copy(o);
	copy.fields().validate(section);
}

}  // namespace keygrid::core
