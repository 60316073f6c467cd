#include <keygrid/core/ImageReading.h>
#include <libdeflate.h>
#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>

namespace keygrid::core
{
namespace
{
std::uint32_t bigEndian32(const std::uint8_t* p)
{
	return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) | p[3];
}

struct PngHeader
{
	std::uint32_t width{0}, height{0};
	int bitDepth{0}, colourType{0};
};

/** PNG colour types (spec 11.2.2). */
constexpr int kGrey = 0, kRgb = 2, kRgba = 6;

int channelsOf(int colourType) { return colourType == kGrey ? 1 : colourType == kRgb ? 3 : colourType == kRgba ? 4 : 0; }

/** Whether the fast path turns this PNG into what cv::imread(flags) gives. */
bool handled(const PngHeader& h, int flags)
{
	if (flags == cv::IMREAD_COLOR) return h.bitDepth == 8 && channelsOf(h.colourType) > 0;
	if (flags == cv::IMREAD_ANYDEPTH) return h.colourType == kGrey && (h.bitDepth == 8 || h.bitDepth == 16);
	return false;
}

/** Undoes the filter of one row in place (spec 9.2). `prev` is the previous row, already
 * unfiltered (all zero for the first row); bpp = bytes per complete pixel. */
bool unfilterRow(int type, std::uint8_t* row, const std::uint8_t* prev, std::size_t n, std::size_t bpp)
{
	switch (type)
	{
		case 0: return true;  // None
		case 1:  // Sub: + left
			for (std::size_t i = bpp; i < n; i++) row[i] = static_cast<std::uint8_t>(row[i] + row[i - bpp]);
			return true;
		case 2:  // Up: + above
			for (std::size_t i = 0; i < n; i++) row[i] = static_cast<std::uint8_t>(row[i] + prev[i]);
			return true;
		case 3:  // Average: + floor((left + above) / 2)
			for (std::size_t i = 0; i < bpp; i++) row[i] = static_cast<std::uint8_t>(row[i] + (prev[i] >> 1));
			for (std::size_t i = bpp; i < n; i++) row[i] = static_cast<std::uint8_t>(row[i] + ((row[i - bpp] + prev[i]) >> 1));
			return true;
		case 4:  // Paeth: + whichever of left, above, upper-left is closest to left + above - upper-left
			for (std::size_t i = 0; i < n; i++)
			{
				const int a = i >= bpp ? row[i - bpp] : 0, b = prev[i], c = i >= bpp ? prev[i - bpp] : 0;
				const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
				row[i] = static_cast<std::uint8_t>(row[i] + ((pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c)));
			}
			return true;
		default: return false;
	}
}

struct DecompressorDeleter
{
	void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};

bool readFile(const std::string& path, std::vector<std::uint8_t>& bytes)
{
	std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
	if (!f) return false;
	if (std::fseek(f.get(), 0, SEEK_END) != 0) return false;
	const long size = std::ftell(f.get());
	if (size < 0 || std::fseek(f.get(), 0, SEEK_SET) != 0) return false;
	bytes.resize(static_cast<std::size_t>(size));
	return std::fread(bytes.data(), 1, bytes.size(), f.get()) == bytes.size();
}
}  // namespace

bool decodePngFast(const std::vector<std::uint8_t>& file, int flags, cv::Mat& out)
{
	static const std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
	if (file.size() < 8 || std::memcmp(file.data(), kSignature, 8) != 0) return false;
	// --- Chunks: IHDR first, IDATs concatenated, up to IEND; CRCs of the critical ones checked.
	PngHeader h;
	std::vector<std::uint8_t> idat;
	bool header = false, end = false;
	for (std::size_t pos = 8; pos + 12 <= file.size() && !end;)
	{
		const std::size_t len = bigEndian32(&file[pos]);
		if (len > file.size() - pos - 12) return false;  // truncated
		const std::uint8_t* type = &file[pos + 4];
		const std::uint8_t* data = type + 4;
		const bool critical = (type[0] & 0x20) == 0;
		if (critical && libdeflate_crc32(0, type, len + 4) != bigEndian32(data + len)) return false;
		if (std::memcmp(type, "IHDR", 4) == 0)
		{
			if (len != 13 || header) return false;
			h.width = bigEndian32(data);
			h.height = bigEndian32(data + 4);
			h.bitDepth = data[8];
			h.colourType = data[9];
			// compression 0, filter method 0, no interlacing
			if (data[10] != 0 || data[11] != 0 || data[12] != 0) return false;
			header = true;
		}
		else if (!header)
			return false;
		else if (std::memcmp(type, "IDAT", 4) == 0)
			idat.insert(idat.end(), data, data + len);
		else if (std::memcmp(type, "IEND", 4) == 0)
			end = true;
		else if (critical)
			return false;  // PLTE (palette) or an unknown critical chunk
		pos += len + 12;
	}
	if (!end || idat.empty() || !handled(h, flags)) return false;
	if (h.width == 0 || h.height == 0 || h.width > (1u << 16) || h.height > (1u << 16)) return false;

	// --- Inflate (the zlib stream's Adler-32 is checked) and unfilter.
	const int channels = channelsOf(h.colourType);
	const std::size_t bpp = static_cast<std::size_t>(channels * h.bitDepth / 8);
	const std::size_t stride = bpp * h.width;
	std::vector<std::uint8_t> raw((stride + 1) * h.height);
	thread_local std::unique_ptr<libdeflate_decompressor, DecompressorDeleter> inflater(libdeflate_alloc_decompressor());
	if (!inflater) return false;
	std::size_t produced = 0;
	if (libdeflate_zlib_decompress(inflater.get(), idat.data(), idat.size(), raw.data(), raw.size(), &produced) != LIBDEFLATE_SUCCESS ||
		produced != raw.size())
		return false;
	const std::vector<std::uint8_t> zeros(stride, 0);
	for (std::uint32_t y = 0; y < h.height; y++)
	{
		std::uint8_t* row = &raw[y * (stride + 1)];
		const std::uint8_t* prev = y ? &raw[(y - 1) * (stride + 1) + 1] : zeros.data();
		if (!unfilterRow(row[0], row + 1, prev, stride, bpp)) return false;
	}

	// --- Into cv::imread's layout: BGR for colour, native-endian 16-bit for depth.
	const int rows = static_cast<int>(h.height), cols = static_cast<int>(h.width);
	cv::Mat m(rows, cols, flags == cv::IMREAD_COLOR ? CV_8UC3 : (h.bitDepth == 16 ? CV_16UC1 : CV_8UC1));
	for (int y = 0; y < rows; y++)
	{
		const std::uint8_t* in = &raw[static_cast<std::size_t>(y) * (stride + 1) + 1];
		if (flags == cv::IMREAD_COLOR)
		{
			auto* o = m.ptr<std::uint8_t>(y);
			for (int x = 0; x < cols; x++, o += 3, in += channels)
			{
				o[0] = in[channels == 1 ? 0 : 2];  // alpha (RGBA) is dropped, as cv::imread does
				o[1] = in[channels == 1 ? 0 : 1];
				o[2] = in[0];
			}
		}
		else if (h.bitDepth == 16)
		{
			auto* o = m.ptr<std::uint16_t>(y);
			for (int x = 0; x < cols; x++) o[x] = static_cast<std::uint16_t>((in[2 * x] << 8) | in[2 * x + 1]);  // PNG is big-endian
		}
		else
			std::memcpy(m.ptr<std::uint8_t>(y), in, stride);
	}
	out = m;
	return true;
}

cv::Mat readImage(const std::string& path, int flags)
{
	if (flags == cv::IMREAD_COLOR || flags == cv::IMREAD_ANYDEPTH)
	{
		std::vector<std::uint8_t> bytes;
		cv::Mat out;
		if (readFile(path, bytes) && decodePngFast(bytes, flags, out)) return out;
	}
	return cv::imread(path, flags);
}

}  // namespace keygrid::core
