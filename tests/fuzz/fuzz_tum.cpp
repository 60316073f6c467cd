/** \file fuzz_tum.cpp
 * libFuzzer target: any bytes as a TUM text file: the associations.txt of a TUM folder
 * (TumSequence) and a trajectory (readTumTrajectory, strict and skipping bad lines).
 */
#include <keygrid/core/TumSequence.h>
#include <keygrid/core/TumTrajectory.h>

#include <cstdint>
#include <stdexcept>

#include "FuzzTempFile.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
	const std::string list = keygrid::fuzz::writeInput("tum/associations.txt", data, size);
	try
	{
		keygrid::core::TumSequence seq(keygrid::fuzz::scratchPath("tum"));
		(void)seq.guessCamera();
	}
	catch (const std::exception&)
	{
	}
	for (const bool skip : {false, true})
	{
		try
		{
			keygrid::core::TrajectoryReadOptions o;
			o.skipBadLines = skip;
			std::vector<keygrid::core::TextLineIssue> issues;
			(void)keygrid::core::readTumTrajectory(list, o, &issues);
		}
		catch (const std::exception&)
		{
		}
	}
	return 0;
}
