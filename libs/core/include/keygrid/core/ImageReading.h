#pragma once
/** \file ImageReading.h
 * Image files in, as cv::imread reads them, with a faster path for the PNGs of RGB-D
 * datasets.
 *
 * Decoding the two PNGs of a TUM frame with cv::imread (libpng + zlib) is a large share of
 * keygrid-slam's CPU time. PNG is a zlib stream of filtered rows: the fast path reads the
 * chunks itself, inflates the image data with libdeflate (faster than zlib) and undoes the row filters (PNG spec, section 9). It handles what RGB-D
 * datasets write: non-interlaced 8-bit grey / RGB / RGBA read as colour, and 8- or 16-bit
 * grey read as depth. Anything else (interlacing, palettes, other bit depths, other formats,
 * a checksum that does not match, a truncated file) goes to cv::imread, so results and
 * errors are cv::imread's in every case.
 */
#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace keygrid::core
{
/** cv::imread(path, flags) for flags cv::IMREAD_COLOR or cv::IMREAD_ANYDEPTH (the same
 * pixels, type and size; empty when the file cannot be read), faster for the PNGs above.
 * Other flags go straight to cv::imread. */
cv::Mat readImage(const std::string& path, int flags);

/** The fast path alone, on the bytes of a file: true and `out` filled when the file is a PNG
 * it handles for `flags` and every checksum matches; false (out untouched) otherwise. */
bool decodePngFast(const std::vector<std::uint8_t>& file, int flags, cv::Mat& out);

}  // namespace keygrid::core
