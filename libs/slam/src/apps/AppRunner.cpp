#include <keygrid/core/CommandLine.h>
#include <keygrid/slam/apps/AppRunner.h>

#include <iostream>

namespace keygrid::slam
{
namespace
{
std::string firstLine(const std::string& s)
{
	// MRPT exceptions carry a multi-line backtrace; the reason is the most specific line.
	std::string best;
	std::size_t start = 0;
	while (start <= s.size())
	{
		auto end = s.find('\n', start);
		if (end == std::string::npos) end = s.size();
		std::string line = s.substr(start, end - start);
		if (!line.empty() && line.find("==== MRPT exception") == std::string::npos)
			best = line;  // MRPT puts the message last
		if (best.empty()) best = line;
		start = end + 1;
		if (s.find("MRPT exception") == std::string::npos && !best.empty()) break;
	}
	return best.empty() ? s : best;
}
}  // namespace

int runApp(const std::string& program, const std::function<int()>& body)
{
	try
	{
		return body();
	}
	catch (const core::CommandLineError& e)
	{
		std::cerr << program << ": error: " << e.what() << " (see " << program << " --help)\n";
		return 2;
	}
	catch (const std::exception& e)
	{
		std::cerr << program << ": error: " << firstLine(e.what()) << "\n";
		return 1;
	}
}

}  // namespace keygrid::slam
