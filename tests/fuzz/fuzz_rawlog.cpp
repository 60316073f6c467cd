/** \file fuzz_rawlog.cpp
 * libFuzzer target: any bytes as a rawlog file, read to the end by RawlogFrameSource (entry
 * check, MRPT's deserialization, frame conversion). An exception is a handled error; a crash,
 * a sanitizer report or a hang is a bug.
 */
#include <keygrid/core/RawlogFrameSource.h>

#include <cstdint>
#include <stdexcept>

#include "FuzzTempFile.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
	const std::string path = keygrid::fuzz::writeInput("input.rawlog", data, size);
	try
	{
		keygrid::core::RawlogFrameSource source(path);
		keygrid::core::Frame f;
		while (source.next(f))
		{
		}
	}
	catch (const std::exception&)
	{
	}
	return 0;
}
