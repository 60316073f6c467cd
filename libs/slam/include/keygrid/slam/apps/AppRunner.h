#pragma once
/** \file AppRunner.h
 * The shared shell of every keygrid tool: run the App, turn exceptions into a one-line reason
 * on stderr and an exit code (2: bad command line, 1: bad input or failure, 0: success).
 */
#include <functional>
#include <string>

namespace keygrid::slam
{
/** Calls body(); returns its exit code, or prints "<program>: error: <reason>" and returns 1
 * (2 for core::CommandLineError). */
int runApp(const std::string& program, const std::function<int()>& body);

}  // namespace keygrid::slam
