/** \file fuzz_png.cpp
 * libFuzzer target: any bytes as a PNG file for keygrid's fast PNG decoder (ImageReading.h),
 * in the two modes the frame sources use (colour, depth). A refused file falls back to OpenCV in
 * readImage; here only the fast decoder runs.
 */
#include <keygrid/core/ImageReading.h>
#include <opencv2/imgcodecs.hpp>

#include <cstdint>
#include <stdexcept>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
	const std::vector<std::uint8_t> file(data, data + size);
	for (const int flags : {cv::IMREAD_COLOR, cv::IMREAD_ANYDEPTH})
	{
		try
		{
			cv::Mat out;
			if (keygrid::core::decodePngFast(file, flags, out) && !out.empty())
			{
				volatile std::uint8_t sink = out.data[out.total() * out.elemSize() - 1];  // the whole buffer is there
				(void)sink;
			}
		}
		catch (const std::exception&)
		{
		}
	}
	return 0;
}
