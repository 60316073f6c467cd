#include <keygrid/store/GzipBlock.h>
#include <zlib.h>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace keygrid::store
{
namespace
{
// windowBits 15 (32 KiB window) + 16 selects the gzip wrapper for deflate; + 32 lets inflate
// accept it.
constexpr int kGzipDeflateBits = 15 + 16;
constexpr int kGzipInflateBits = 15 + 32;
constexpr std::size_t kChunk = std::size_t{1} << 20;

std::string zlibMessage(const z_stream& z, int code)
{
	return z.msg ? std::string(z.msg) : "zlib error " + std::to_string(code);
}
}  // namespace

std::vector<std::uint8_t> gzipCompress(const std::vector<std::uint8_t>& data, int level)
{
	if (level < 1 || level > 9) throw std::invalid_argument("gzipCompress: level must be in 1..9, got " + std::to_string(level));
	if (data.size() > std::numeric_limits<uInt>::max())
		throw std::invalid_argument("gzipCompress: a block of " + std::to_string(data.size()) + " bytes is over zlib's 4 GiB limit");
	z_stream z{};
	int rc = deflateInit2(&z, level, Z_DEFLATED, kGzipDeflateBits, 8, Z_DEFAULT_STRATEGY);
	if (rc != Z_OK) throw std::runtime_error("gzipCompress: " + zlibMessage(z, rc));
	std::vector<std::uint8_t> out(deflateBound(&z, static_cast<uLong>(data.size())));
	z.next_in = const_cast<Bytef*>(data.data());
	z.avail_in = static_cast<uInt>(data.size());
	z.next_out = out.data();
	z.avail_out = static_cast<uInt>(out.size());
	rc = deflate(&z, Z_FINISH);  // deflateBound guarantees one call suffices
	const std::size_t written = z.total_out;
	const std::string msg = zlibMessage(z, rc);
	deflateEnd(&z);
	if (rc != Z_STREAM_END) throw std::runtime_error("gzipCompress: " + msg);
	out.resize(written);
	return out;
}

std::vector<std::uint8_t> gzipDecompress(const std::vector<std::uint8_t>& gz, std::size_t maxBytes)
{
	if (gz.size() > std::numeric_limits<uInt>::max())
		throw std::runtime_error("gzip data of " + std::to_string(gz.size()) + " bytes is over zlib's 4 GiB limit");
	z_stream z{};
	int rc = inflateInit2(&z, kGzipInflateBits);
	if (rc != Z_OK) throw std::runtime_error("gzip: " + zlibMessage(z, rc));
	z.next_in = const_cast<Bytef*>(gz.data());
	z.avail_in = static_cast<uInt>(gz.size());
	// One byte over the bound tells a stream of exactly maxBytes from a longer one.
	const std::size_t limit = maxBytes == std::numeric_limits<std::size_t>::max() ? maxBytes : maxBytes + 1;
	std::vector<std::uint8_t> out;
	std::string error;
	while (true)
	{
		const std::size_t have = out.size();
		if (have > maxBytes)
		{
			error = "gzip data inflates to more than " + std::to_string(maxBytes) + " bytes";
			break;
		}
		const std::size_t grow = std::min({kChunk, limit - have, std::size_t{std::numeric_limits<uInt>::max()}});
		out.resize(have + grow);
		z.next_out = out.data() + have;
		z.avail_out = static_cast<uInt>(grow);
		rc = inflate(&z, Z_NO_FLUSH);
		out.resize(have + (grow - z.avail_out));
		if (rc == Z_STREAM_END)
		{
			if (out.size() > maxBytes) error = "gzip data inflates to more than " + std::to_string(maxBytes) + " bytes";
			break;
		}
		if (rc == Z_BUF_ERROR && z.avail_in == 0)
		{
			error = "gzip data is truncated";
			break;
		}
		if (rc != Z_OK && rc != Z_BUF_ERROR)
		{
			error = "gzip data is damaged: " + zlibMessage(z, rc);
			break;
		}
	}
	const bool trailing = error.empty() && z.avail_in != 0;
	inflateEnd(&z);
	if (!error.empty()) throw std::runtime_error(error);
	if (trailing) throw std::runtime_error("gzip data has " + std::to_string(z.avail_in) + " bytes after the end of its stream");
	return out;
}

}  // namespace keygrid::store
