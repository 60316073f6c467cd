/** \file GzipBlock_unittest.cpp
 * In-memory gzip: round trips checked against libdeflate (an independent DEFLATE/gzip
 * implementation), damaged streams refused with their reason, the inflate bound, and map
 * snapshots encoded from two threads at once (MRPT's file-based compress_gz_data_block
 * mixes up the data of compressions made in the same second).
 */
#include <keygrid/store/GzipBlock.h>
#include <keygrid/store/MapSnapshotCodec.h>
#include <gtest/gtest.h>
#include <libdeflate.h>
#include <mrpt/maps/CSimplePointsMap.h>

#include <random>
#include <stdexcept>
#include <thread>

using namespace keygrid::store;

namespace
{
std::vector<std::uint8_t> compressibleBytes(std::size_t n, unsigned seed)
{
	std::mt19937 rng(seed);
	std::vector<std::uint8_t> v(n);
	for (auto& b : v) b = static_cast<std::uint8_t>(rng() % 16);  // 4 bits of entropy per byte
	return v;
}

std::vector<std::uint8_t> libdeflateGunzip(const std::vector<std::uint8_t>& gz, std::size_t size)
{
	std::vector<std::uint8_t> out(size + 1);
	auto* d = libdeflate_alloc_decompressor();
	std::size_t actual = 0;
	const auto r = libdeflate_gzip_decompress(d, gz.data(), gz.size(), out.data(), out.size(), &actual);
	libdeflate_free_decompressor(d);
	if (r != LIBDEFLATE_SUCCESS) throw std::runtime_error("libdeflate refused the stream");
	out.resize(actual);
	return out;
}

std::vector<std::uint8_t> libdeflateGzip(const std::vector<std::uint8_t>& data)
{
	auto* c = libdeflate_alloc_compressor(6);
	std::vector<std::uint8_t> out(libdeflate_gzip_compress_bound(c, data.size()));
	out.resize(libdeflate_gzip_compress(c, data.data(), data.size(), out.data(), out.size()));
	libdeflate_free_compressor(c);
	return out;
}

std::string errorOf(const std::vector<std::uint8_t>& gz, std::size_t maxBytes)
{
	try
	{
		gzipDecompress(gz, maxBytes);
	}
	catch (const std::runtime_error& e)
	{
		return e.what();
	}
	return "";
}
}  // namespace

TEST(GzipBlock, RoundTripsAgainstAnIndependentImplementation)
{
	for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{1000}, std::size_t{3} << 20})
		for (const int level : {1, 9})
		{
			const auto data = compressibleBytes(n, static_cast<unsigned>(n + level));
			const auto gz = gzipCompress(data, level);
			if (n >= 1000)
			{
				EXPECT_LT(gz.size(), n * 6 / 10) << "4-bit symbols compress to about half";
			}
			EXPECT_EQ(libdeflateGunzip(gz, n), data) << n << " bytes, level " << level;
			EXPECT_EQ(gzipDecompress(gz, n), data);
			EXPECT_EQ(gzipDecompress(libdeflateGzip(data), n), data);
		}
	EXPECT_THROW(gzipCompress({1, 2, 3}, 0), std::invalid_argument);
	EXPECT_THROW(gzipCompress({1, 2, 3}, 10), std::invalid_argument);
}

TEST(GzipBlock, DamagedTruncatedOrOversizedStreamsAreRefusedWithTheirReason)
{
	const auto data = compressibleBytes(100000, 7);
	const auto gz = gzipCompress(data, 6);

	auto truncated = gz;
	truncated.resize(gz.size() / 2);
	EXPECT_NE(errorOf(truncated, data.size()).find("truncated"), std::string::npos);
	EXPECT_NE(errorOf({}, data.size()).find("truncated"), std::string::npos);

	auto badCrc = gz;
	badCrc[gz.size() - 6] ^= 0x01;  // the CRC-32 in the gzip trailer
	EXPECT_NE(errorOf(badCrc, data.size()).find("damaged"), std::string::npos);

	auto notGzip = gz;
	notGzip[0] = 'P';
	EXPECT_NE(errorOf(notGzip, data.size()).find("damaged"), std::string::npos);

	auto trailing = gz;
	trailing.push_back(0);
	EXPECT_NE(errorOf(trailing, data.size()).find("1 bytes after the end"), std::string::npos);

	// The bound: exactly the size passes, one byte less is refused.
	EXPECT_EQ(gzipDecompress(gz, data.size()), data);
	EXPECT_NE(errorOf(gz, data.size() - 1).find("more than 99999 bytes"), std::string::npos);
}

TEST(GzipBlock, SnapshotsEncodedInTwoThreadsAtOnceDecodeToTheirOwnMaps)
{
	// Two maps of different content, encoded over and over from two threads in the same second.
	auto makeMap = [](float offset, std::size_t n) {
		mrpt::maps::CSimplePointsMap m;
		for (std::size_t i = 0; i < n; i++) m.insertPoint(offset + 0.01f * i, 0.5f * offset, 1.0f);
		return m;
	};
	const auto a = makeMap(1.0f, 20000), b = makeMap(-3.0f, 30000);
	std::vector<MapSnapshot> sa(40), sb(40);
	std::thread ta([&] {
		for (auto& s : sa) s = MapSnapshotCodec::encode("a", a, 1);
	});
	std::thread tb([&] {
		for (auto& s : sb) s = MapSnapshotCodec::encode("b", b, 2);
	});
	ta.join();
	tb.join();
	for (std::size_t k = 0; k < sa.size(); k++)
	{
		const auto da = std::dynamic_pointer_cast<mrpt::maps::CSimplePointsMap>(MapSnapshotCodec::decode(sa[k]));
		const auto db = std::dynamic_pointer_cast<mrpt::maps::CSimplePointsMap>(MapSnapshotCodec::decode(sb[k]));
		ASSERT_TRUE(da && db) << k;
		ASSERT_EQ(da->size(), a.size()) << k;
		ASSERT_EQ(db->size(), b.size()) << k;
		EXPECT_EQ(da->getPointsBufferRef_x()[123], a.getPointsBufferRef_x()[123]);
		EXPECT_EQ(db->getPointsBufferRef_x()[123], b.getPointsBufferRef_x()[123]);
	}
}
