#pragma once
/** \file FieldTableOptions.h
 * Base of the options structs whose INI keys are one core::OptionFields table (OptionFields.h):
 * Derived gives `fields()`, and may give its own `validate(section) const` for rules across
 * keys; reading, writing and MRPT's dump follow. An MRPT CLoadableOptions, so the map plugins'
 * structs are read by CMultiMetricMap from the `<map>_creationOpts` / `_insertOpts` /
 * `_likelihoodOpts` sections like MRPT's own.
 */
#include <keygrid/core/OptionFields.h>
#include <mrpt/config/CLoadableOptions.h>

#include <string>

namespace keygrid::core
{
template <class Derived>
struct FieldTableOptions : public mrpt::config::CLoadableOptions
{
	/** Reads every key of the table (absent keys keep their value), then validate(section):
	 * throws std::invalid_argument naming [section], key and value. */
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& source, const std::string& section) override
	{
		auto& self = static_cast<Derived&>(*this);
		self.fields().read(source, section);
		self.validate(section);
	}
	/** Writes every key of the table with its description. */
	void saveToConfigFile(mrpt::config::CConfigFileBase& target, const std::string& section) const override
	{
		writeFields(static_cast<const Derived&>(*this), target, section);
	}
	/** The table's own rules; a Derived with rules across keys declares its own. */
	void validate(const std::string& section) const { validateFields(static_cast<const Derived&>(*this), section); }
};

}  // namespace keygrid::core
