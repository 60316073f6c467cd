#pragma once
/** \file GzipBlock.h
 * Gzip (RFC 1952) compression of a byte block in memory, through zlib.
 *
 * MRPT's mrpt::io::zip::compress_gz_data_block goes through a file named after the current
 * second (/tmp/mrpt_compress_gz_data_block_<time_t>), so two compressions in the same second,
 * from two threads or two processes, overwrite each other's data. These functions share no
 * state and touch no file.
 */
#include <cstddef>
#include <cstdint>
#include <vector>

namespace keygrid::store
{
/** The gzip stream of `data` at zlib level `level` (1 .. 9). Throws std::invalid_argument on a
 * bad level, std::runtime_error when zlib fails. */
std::vector<std::uint8_t> gzipCompress(const std::vector<std::uint8_t>& data, int level);

/** The bytes of a gzip stream. Throws std::runtime_error when `gz` is not one complete gzip
 * stream (damaged, truncated, or with trailing bytes) or when it would inflate to more than
 * `maxBytes`, which bounds the memory a damaged or hostile input can claim. */
std::vector<std::uint8_t> gzipDecompress(const std::vector<std::uint8_t>& gz, std::size_t maxBytes);

}  // namespace keygrid::store
