#include <keygrid/core/CommandLine.h>
#include <keygrid/slam/apps/AppRunner.h>

#include <algorithm>
#include <iostream>
#include <string>

namespace keygrid::slam
{
namespace
{
std::string lineStartingWith(const std::string& s, const std::string& prefix, bool* found)
{
	const auto at = s.find("\n" + prefix);
	*found = at != std::string::npos;
	if (!*found) return "";
	const auto begin = at + 1 + prefix.size();
	return s.substr(begin, s.find('\n', begin) - begin);
}

/** The reason of an error as one line. An MRPT exception reads "==== MRPT exception ====",
 * "Message: ...", "Location: ...", then a backtrace. Wrapping a std::exception, MRPT cuts its
 * text at the last ']': the part before it is printed as the Location, the rest as the
 * Message; joined again they are the original reason. */
std::string firstLine(const std::string& s)
{
	if (s.find("==== MRPT exception ====") == std::string::npos) return s.substr(0, s.find('\n'));
	bool hasMessage = false, hasLocation = false;
	std::string message = lineStartingWith(s, "Message:", &hasMessage);
	std::string location = lineStartingWith(s, "Location:", &hasLocation);
	if (!message.empty() && message[0] == ' ') message.erase(0, 1);
	if (!location.empty() && location[0] == ' ') location.erase(0, 1);
	const auto opened = std::count(location.begin(), location.end(), '['), closed = std::count(location.begin(), location.end(), ']');
	if (hasLocation && opened > closed) return location + "]" + message;
	if (!message.empty()) return message;
	if (!location.empty()) return location;
	return s.substr(0, s.find('\n'));
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
