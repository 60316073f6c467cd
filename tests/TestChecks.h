#pragma once
/** \file TestChecks.h
 * Small checks shared by the test suites:
 * - errorOf<E>(f): the message of the E that f() throws, "" when it throws nothing;
 * - sameBits(a, b): two images with the same size, type and bytes (no tolerance).
 */
#include <opencv2/core.hpp>

#include <cstring>
#include <stdexcept>
#include <string>

namespace keygrid::test
{
template <class Error = std::invalid_argument, class F>
std::string errorOf(F&& f)
{
	try
	{
		f();
	}
	catch (const Error& e)
	{
		return e.what();
	}
	return "";
}

inline bool sameBits(const cv::Mat& a, const cv::Mat& b)
{
	if (a.empty() || b.empty()) return a.empty() && b.empty();
	if (a.size() != b.size() || a.type() != b.type()) return false;
	for (int r = 0; r < a.rows; r++)
		if (std::memcmp(a.ptr(r), b.ptr(r), a.cols * a.elemSize()) != 0) return false;
	return true;
}
}  // namespace keygrid::test
