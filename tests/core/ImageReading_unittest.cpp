// The fast PNG path of core::readImage against cv::imread (libpng), the independent
// implementation: the same pixels for PNGs OpenCV writes, for hand-built PNGs that use every
// row filter, and for the real TUM images; damaged or unsupported files go to cv::imread.
#include <keygrid/core/ImageReading.h>
#include <libdeflate.h>
#include <opencv2/imgcodecs.hpp>

#include "TestChecks.h"
#include "TestData.h"

#include <cstdio>
#include <fstream>
#include <random>

using namespace keygrid;
using keygrid::test::sameBits;

namespace
{
/** Noise over gradients: libpng's adaptive filtering then picks different filters per row. */
cv::Mat testImage(int rows, int cols, int type, unsigned seed)
{
	cv::Mat m(rows, cols, type);
	std::mt19937 g(seed);
	const int channels = m.channels();
	for (int y = 0; y < rows; y++)
		for (int x = 0; x < cols * channels; x++)
		{
			const int base = (x * 7 + y * 3) % 256 + static_cast<int>(g() % (y % 4 == 0 ? 64 : 3));
			if (m.depth() == CV_16U) m.ptr<std::uint16_t>(y)[x] = static_cast<std::uint16_t>(base * 200 + g() % 50);
			else
				m.ptr<std::uint8_t>(y)[x] = static_cast<std::uint8_t>(base);
		}
	return m;
}

std::vector<std::uint8_t> fileBytes(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	return {std::istreambuf_iterator<char>(f), {}};
}

void writeBytes(const std::string& path, const std::vector<std::uint8_t>& b)
{
	std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

void put32(std::vector<std::uint8_t>& out, std::uint32_t v)
{
	for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<std::uint8_t>(v >> s));
}

void chunk(std::vector<std::uint8_t>& png, const char* type, const std::vector<std::uint8_t>& data)
{
	put32(png, static_cast<std::uint32_t>(data.size()));
	const std::size_t start = png.size();
	png.insert(png.end(), type, type + 4);
	png.insert(png.end(), data.begin(), data.end());
	put32(png, libdeflate_crc32(0, &png[start], data.size() + 4));
}

/** A PNG of `pixels` (PNG byte order: RGB(A), big-endian 16-bit) whose row y uses filter
 * y % 5 (None, Sub, Up, Average, Paeth), written independently of libpng. */
std::vector<std::uint8_t> handBuiltPng(
	const std::vector<std::uint8_t>& pixels, int width, int height, int bitDepth, int colourType, int bpp, int interlace = 0)
{
	const std::size_t stride = static_cast<std::size_t>(width) * bpp;
	std::vector<std::uint8_t> filtered;
	for (int y = 0; y < height; y++)
	{
		const int type = y % 5;
		filtered.push_back(static_cast<std::uint8_t>(type));
		const std::uint8_t* row = &pixels[y * stride];
		const std::uint8_t* up = y ? &pixels[(y - 1) * stride] : nullptr;
		for (std::size_t i = 0; i < stride; i++)
		{
			const int a = i >= static_cast<std::size_t>(bpp) ? row[i - bpp] : 0, b = up ? up[i] : 0,
					  c = up && i >= static_cast<std::size_t>(bpp) ? up[i - bpp] : 0;
			const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
			const int pred[5] = {0, a, b, (a + b) / 2, (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c)};
			filtered.push_back(static_cast<std::uint8_t>(row[i] - pred[type]));
		}
	}
	libdeflate_compressor* comp = libdeflate_alloc_compressor(6);
	std::vector<std::uint8_t> z(libdeflate_zlib_compress_bound(comp, filtered.size()));
	z.resize(libdeflate_zlib_compress(comp, filtered.data(), filtered.size(), z.data(), z.size()));
	libdeflate_free_compressor(comp);

	std::vector<std::uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
	std::vector<std::uint8_t> ihdr;
	put32(ihdr, static_cast<std::uint32_t>(width));
	put32(ihdr, static_cast<std::uint32_t>(height));
	ihdr.insert(ihdr.end(), {static_cast<std::uint8_t>(bitDepth), static_cast<std::uint8_t>(colourType), 0, 0, static_cast<std::uint8_t>(interlace)});
	chunk(png, "IHDR", ihdr);
	chunk(png, "tEXt", {'k', 0, 'v'});  // an ancillary chunk to skip
	// The image data split over two IDAT chunks, as encoders do for large images.
	const std::size_t half = z.size() / 2;
	chunk(png, "IDAT", {z.begin(), z.begin() + static_cast<std::ptrdiff_t>(half)});
	chunk(png, "IDAT", {z.begin() + static_cast<std::ptrdiff_t>(half), z.end()});
	chunk(png, "IEND", {});
	return png;
}

std::vector<std::uint8_t> randomBytes(std::size_t n, unsigned seed)
{
	std::mt19937 g(seed);
	std::vector<std::uint8_t> v(n);
	for (auto& b : v) b = static_cast<std::uint8_t>(g() % 256 < 200 ? g() % 40 : g());  // compressible
	return v;
}
}  // namespace

TEST(ImageReading, PngsWrittenByOpenCvReadAsImreadReadsThem)
{
	const std::string dir = test::scratchDir("image_reading_opencv");
	int fast = 0, cases = 0;
	for (int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1})
		for (const cv::Size size : {cv::Size(640, 480), cv::Size(33, 17), cv::Size(1, 1)})
			for (int level : {0, 1, 9})
				for (int strategy : {cv::IMWRITE_PNG_STRATEGY_DEFAULT, cv::IMWRITE_PNG_STRATEGY_FILTERED, cv::IMWRITE_PNG_STRATEGY_RLE})
				{
					const std::string path = dir + "/img.png";
					ASSERT_TRUE(cv::imwrite(path, testImage(size.height, size.width, type, static_cast<unsigned>(cases)),
											{cv::IMWRITE_PNG_COMPRESSION, level, cv::IMWRITE_PNG_STRATEGY, strategy}));
					for (int flags : {cv::IMREAD_COLOR, cv::IMREAD_ANYDEPTH})
					{
						EXPECT_TRUE(sameBits(core::readImage(path, flags), cv::imread(path, flags)))
							<< "type " << type << " size " << size << " level " << level << " flags " << flags;
						cv::Mat m;
						fast += core::decodePngFast(fileBytes(path), flags, m);
						cases++;
					}
				}
	// 27 files per type. The fast path takes 8-bit grey, RGB and RGBA read as colour and 8- and
	// 16-bit grey read as depth; 16-bit read as colour and colour read as depth are
	// cv::imread's conversions and stay with it.
	EXPECT_EQ(fast, 27 * 3 + 27 * 2);
}

TEST(ImageReading, EveryRowFilterIsUndone)
{
	const std::string dir = test::scratchDir("image_reading_filters");
	struct Kind
	{
		int bitDepth, colourType, bpp, flags;
	};
	for (const Kind k : {Kind{8, 0, 1, cv::IMREAD_ANYDEPTH}, Kind{8, 2, 3, cv::IMREAD_COLOR}, Kind{8, 6, 4, cv::IMREAD_COLOR},
						 Kind{16, 0, 2, cv::IMREAD_ANYDEPTH}, Kind{8, 0, 1, cv::IMREAD_COLOR}})
	{
		const int w = 37, h = 23;
		const auto pixels = randomBytes(static_cast<std::size_t>(w) * h * k.bpp, static_cast<unsigned>(k.bpp * 10 + k.flags));
		const auto png = handBuiltPng(pixels, w, h, k.bitDepth, k.colourType, k.bpp);
		cv::Mat fast;
		ASSERT_TRUE(core::decodePngFast(png, k.flags, fast)) << "bit depth " << k.bitDepth << " colour type " << k.colourType;
		writeBytes(dir + "/f.png", png);
		EXPECT_TRUE(sameBits(fast, cv::imread(dir + "/f.png", k.flags))) << "colour type " << k.colourType;
		// And against the pixels themselves (the first channel of the first and last pixel).
		const std::size_t last = pixels.size() - k.bpp;
		if (k.bitDepth == 16)
			EXPECT_EQ(fast.at<std::uint16_t>(h - 1, w - 1), (pixels[last] << 8) | pixels[last + 1]);
		else if (k.flags == cv::IMREAD_COLOR)
			EXPECT_EQ(fast.at<cv::Vec3b>(h - 1, w - 1)[2], pixels[last]);  // R of RGB(A) is BGR's third
		else
			EXPECT_EQ(fast.at<std::uint8_t>(0, 0), pixels[0]);
	}
}

TEST(ImageReading, DamagedAndUnsupportedFilesGoToImread)
{
	const std::string dir = test::scratchDir("image_reading_damaged");
	const int w = 40, h = 30;
	const auto pixels = randomBytes(static_cast<std::size_t>(w) * h * 3, 5);
	const auto good = handBuiltPng(pixels, w, h, 8, 2, 3);
	cv::Mat m;
	ASSERT_TRUE(core::decodePngFast(good, cv::IMREAD_COLOR, m));

	auto declined = [&](const std::vector<std::uint8_t>& bytes, const std::string& what) {
		cv::Mat out;
		EXPECT_FALSE(core::decodePngFast(bytes, cv::IMREAD_COLOR, out)) << what;
		EXPECT_TRUE(out.empty()) << what;
		writeBytes(dir + "/d.png", bytes);
		EXPECT_TRUE(sameBits(core::readImage(dir + "/d.png", cv::IMREAD_COLOR), cv::imread(dir + "/d.png", cv::IMREAD_COLOR))) << what;
	};
	for (std::size_t cut : {std::size_t{4}, std::size_t{20}, good.size() / 2, good.size() - 13, good.size() - 1})
		declined({good.begin(), good.begin() + static_cast<std::ptrdiff_t>(cut)}, "truncated at " + std::to_string(cut));
	auto flipped = good;
	flipped[good.size() / 2] ^= 0x10;  // inside the image data: its CRC no longer matches
	declined(flipped, "flipped byte");
	declined(handBuiltPng(pixels, w, h, 8, 2, 3, 1), "interlaced");
	declined(handBuiltPng(pixels, w, h, 8, 3, 1), "palette");
	declined(handBuiltPng(pixels, w / 2, h, 16, 2, 6), "16-bit RGB");
	declined({'n', 'o', 't', ' ', 'a', ' ', 'p', 'n', 'g', '!'}, "not a PNG");
	EXPECT_TRUE(core::readImage(dir + "/no_such_file.png", cv::IMREAD_COLOR).empty());
}

TEST(ImageReading, RealTumImagesReadAsImreadReadsThem)
{
	KEYGRID_SKIP_WITHOUT_SHARED_DATA("tum_fr1_rpy_first250");
	const std::string d = test::sharedDataDir() + "/tum_fr1_rpy_first250/";
	std::ifstream assoc(d + "associations.txt");
	std::string line;
	int checked = 0;
	while (std::getline(assoc, line) && checked < 20)
	{
		if (line.empty() || line[0] == '#') continue;
		char rgb[256], depth[256];
		double t1, t2;
		if (std::sscanf(line.c_str(), "%lf %255s %lf %255s", &t1, rgb, &t2, depth) != 4) continue;
		cv::Mat c, z;
		ASSERT_TRUE(core::decodePngFast(fileBytes(d + rgb), cv::IMREAD_COLOR, c)) << rgb;
		ASSERT_TRUE(core::decodePngFast(fileBytes(d + depth), cv::IMREAD_ANYDEPTH, z)) << depth;
		EXPECT_TRUE(sameBits(c, cv::imread(d + rgb, cv::IMREAD_COLOR))) << rgb;
		EXPECT_TRUE(sameBits(z, cv::imread(d + depth, cv::IMREAD_ANYDEPTH))) << depth;
		checked++;
	}
	EXPECT_EQ(checked, 20);
}
