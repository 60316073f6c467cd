#include <keygrid/core/CommandLine.h>
#include <keygrid/core/TumText.h>

#include <iostream>
#include <sstream>

namespace keygrid::core
{
CommandLine::CommandLine(std::string program, std::string summary)
	: m_program(std::move(program)), m_summary(std::move(summary))
{
	flag("help", "show this help and exit");
}

CommandLine& CommandLine::option(
	const std::string& name, const std::string& valueName, const std::string& help, bool required,
	const std::string& def)
{
	m_order.push_back(name);
	m_opts[name] = Opt{valueName, help, def, required, false};
	return *this;
}

CommandLine& CommandLine::flag(const std::string& name, const std::string& help)
{
	m_order.push_back(name);
	m_opts[name] = Opt{"", help, "", false, true};
	return *this;
}

CommandLine& CommandLine::positionals(const std::string& usage, const std::string& help)
{
	m_acceptPositional = true;
	m_posUsage = usage;
	m_posHelp = help;
	return *this;
}

bool CommandLine::parse(int argc, const char* const* argv)
{
	for (int i = 1; i < argc; i++)
	{
		std::string a = argv[i];
		if (a == "-h") a = "--help";
		if (a.rfind("--", 0) != 0)
		{
			if (!m_acceptPositional) throw CommandLineError("unexpected argument '" + a + "'");
			m_positional.push_back(a);
			continue;
		}
		std::string name = a.substr(2), value;
		bool inlineValue = false;
		if (const auto eq = name.find('='); eq != std::string::npos)
		{
			value = name.substr(eq + 1);
			name.resize(eq);
			inlineValue = true;
		}
		const auto it = m_opts.find(name);
		if (it == m_opts.end()) throw CommandLineError("unknown option --" + name);
		if (it->second.isFlag)
		{
			if (inlineValue) throw CommandLineError("option --" + name + " takes no value");
			m_values[name] = "1";
			continue;
		}
		if (!inlineValue)
		{
			if (i + 1 >= argc) throw CommandLineError("option --" + name + " needs a value");
			value = argv[++i];
		}
		m_values[name] = value;
	}
	if (flagSet("help"))
	{
		std::cout << helpText();
		return false;
	}
	for (const auto& n : m_order)
		if (m_opts.at(n).required && !has(n)) throw CommandLineError("missing --" + n);
	return true;
}

std::string CommandLine::helpText() const
{
	std::ostringstream o;
	o << "Usage: " << m_program;
	if (m_acceptPositional) o << " " << m_posUsage;
	for (const auto& n : m_order)
	{
		const Opt& op = m_opts.at(n);
		if (n == "help") continue;
		std::string s = "--" + n + (op.isFlag ? "" : " " + op.valueName);
		o << " " << (op.required ? s : "[" + s + "]");
	}
	o << "\n\n" << m_summary << "\n\n";
	if (m_acceptPositional) o << "  " << m_posUsage << "\n      " << m_posHelp << "\n";
	for (const auto& n : m_order)
	{
		const Opt& op = m_opts.at(n);
		o << "  --" << n << (op.isFlag ? "" : " " + op.valueName) << "\n      " << op.help;
		if (!op.def.empty()) o << " (default: " << op.def << ")";
		if (op.required) o << " (required)";
		o << "\n";
	}
	return o.str();
}

bool CommandLine::has(const std::string& name) const { return m_values.count(name) > 0; }

std::string CommandLine::get(const std::string& name) const
{
	if (auto it = m_values.find(name); it != m_values.end()) return it->second;
	const auto o = m_opts.find(name);
	if (o == m_opts.end()) throw std::logic_error("undeclared option --" + name);
	return o->second.def;
}

double CommandLine::getDouble(const std::string& name) const
{
	const std::string v = get(name);
	double d = 0;
	if (!parseDouble(v, d)) throw CommandLineError("--" + name + " expects a number, got '" + v + "'");
	return d;
}

long CommandLine::getInt(const std::string& name) const
{
	const std::string v = get(name);
	std::size_t used = 0;
	long d = 0;
	try
	{
		d = std::stol(v, &used);
	}
	catch (const std::exception&)
	{
		used = 0;
	}
	if (used != v.size() || v.empty())
		throw CommandLineError("--" + name + " expects an integer, got '" + v + "'");
	return d;
}

bool CommandLine::flagSet(const std::string& name) const { return has(name); }

}  // namespace keygrid::core
