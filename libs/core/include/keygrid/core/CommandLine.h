#pragma once
/** \file CommandLine.h
 * Minimal `--key value` / `--flag` parser shared by the keygrid tools: generated `--help`,
 * and one-line errors ("unknown option --foo", "missing --input") as exceptions.
 */
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace keygrid::core
{
/** Thrown for bad command lines; what() is the one-line reason. */
struct CommandLineError : std::runtime_error
{
	using std::runtime_error::runtime_error;
};

class CommandLine
{
   public:
	CommandLine(std::string program, std::string summary);

	/** Declares `--name VALUE`. An empty default with required=true makes it mandatory. */
	CommandLine& option(
		const std::string& name, const std::string& valueName, const std::string& help,
		bool required = false, const std::string& defaultValue = "");
	/** Declares a boolean `--name`. */
	CommandLine& flag(const std::string& name, const std::string& help);
	/** Accepts bare positional words (e.g. a sub-command); `help` documents them. */
	CommandLine& positionals(const std::string& usage, const std::string& help);

	/** Parses argv. Returns false when --help was given (help text already printed to stdout).
	 * Throws CommandLineError on unknown options, missing values or missing required options. */
	bool parse(int argc, const char* const* argv);

	std::string helpText() const;

	bool has(const std::string& name) const;                  //!< given on the command line
	std::string get(const std::string& name) const;           //!< value or default
	double getDouble(const std::string& name) const;          //!< throws naming the option
	long getInt(const std::string& name) const;               //!< throws naming the option
	bool flagSet(const std::string& name) const;
	const std::vector<std::string>& positional() const { return m_positional; }

   private:
	struct Opt
	{
		std::string valueName, help, def;
		bool required{false}, isFlag{false};
	};
	std::string m_program, m_summary, m_posUsage, m_posHelp;
	bool m_acceptPositional{false};
	std::vector<std::string> m_order;
	std::map<std::string, Opt> m_opts;
	std::map<std::string, std::string> m_values;
	std::vector<std::string> m_positional;
};

}  // namespace keygrid::core
