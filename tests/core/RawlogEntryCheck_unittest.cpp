/** \file RawlogEntryCheck_unittest.cpp
 * The size check ahead of MRPT's deserialization: intact entries pass and deserialize through
 * the replayed prefix exactly as they were written; damaged range image and point counts are
 * named; a truncated entry passes the check and is left for the deserializer to report.
 */
#include <keygrid/core/RawlogEntryCheck.h>
#include <gtest/gtest.h>
#include <mrpt/img/CImage.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cstring>

using namespace keygrid::core;
using mrpt::obs::CObservation3DRangeScan;

namespace
{
CObservation3DRangeScan::Ptr observation(std::size_t points)
{
	auto o = CObservation3DRangeScan::Create();
	o->hasRangeImage = true;
	o->rangeUnits = 1e-3f;
	o->rangeImage.setSize(30, 40);
	for (int r = 0; r < 30; r++)
		for (int c = 0; c < 40; c++) o->rangeImage(r, c) = static_cast<uint16_t>(1000 + 7 * r + c);
	o->cameraParams.ncols = 40;
	o->cameraParams.nrows = 30;
	o->hasPoints3D = points > 0;
	o->resizePoints3DVectors(points);
	for (std::size_t k = 0; k < points; k++) o->points3D_x[k] = static_cast<float>(k);
	return o;
}

std::vector<std::uint8_t> serialize(const mrpt::serialization::CSerializable& obj)
{
	mrpt::io::CMemoryStream m;
	mrpt::serialization::archiveFrom(m) << obj;
	const auto* p = static_cast<const std::uint8_t*>(m.getRawBufferData());
	return {p, p + m.getTotalBytesCount()};
}

/** Offset of the range image's (rows, cols) = (30, 40) in a serialized entry. */
std::size_t rowsColsOffset(const std::vector<std::uint8_t>& b)
{
	const std::uint32_t rc[2] = {30, 40};
	for (std::size_t i = 0; i + 8 <= b.size(); i++)
		if (std::memcmp(b.data() + i, rc, 8) == 0) return i;
	return b.size();
}

std::string check(const std::vector<std::uint8_t>& bytes, std::vector<std::uint8_t>* consumed = nullptr)
{
	mrpt::io::CMemoryStream in;
	in.assignMemoryNotOwn(bytes.data(), bytes.size());
	std::vector<std::uint8_t> head;
	RawlogEntryLimits l;
	l.bytesLeft = bytes.size();
	const auto why = checkRawlogEntry(in, head, l);
	if (consumed) *consumed = head;
	return why;
}
}  // namespace

TEST(RawlogEntryCheck, IntactEntriesPassAndDeserializeThroughTheReplayedPrefix)
{
	for (const std::size_t points : {std::size_t{0}, std::size_t{50}})
	{
		const auto obs = observation(points);
		const auto bytes = serialize(*obs);
		mrpt::io::CMemoryStream in;
		in.assignMemoryNotOwn(bytes.data(), bytes.size());
		std::vector<std::uint8_t> head;
		RawlogEntryLimits l;
		l.bytesLeft = bytes.size();
		EXPECT_EQ(checkRawlogEntry(in, head, l), "");
		// The walk went to the end of the entry: all but its end-of-object byte.
		EXPECT_EQ(head.size(), bytes.size() - 1) << points << " points";
		EXPECT_EQ(bytes.back(), 0x88);
		PrefixedStream replay(head, in);
		EXPECT_EQ(replay.getPosition(), 0u);
		auto back = std::dynamic_pointer_cast<CObservation3DRangeScan>(mrpt::serialization::archiveFrom(replay).ReadObject());
		ASSERT_TRUE(back);
		EXPECT_EQ(back->rangeImage, obs->rangeImage);
		EXPECT_EQ(back->points3D_x, obs->points3D_x);
		EXPECT_EQ(replay.getPosition(), bytes.size());
	}
	// Inside a sensory frame too.
	mrpt::obs::CSensoryFrame sf;
	sf.insert(observation(0));
	EXPECT_EQ(check(serialize(sf)), "");
}

TEST(RawlogEntryCheck, DamagedSizesAreNamed)
{
	const auto bytes = serialize(*observation(0));
	const std::size_t at = rowsColsOffset(bytes);
	ASSERT_LT(at, bytes.size());

	auto hugeCols = bytes;
	hugeCols[at + 7] = 0x7f;  // the high byte of cols
	EXPECT_EQ(check(hugeCols), "CObservation3DRangeScan range image of 2130706472 x 30 pixels (a side over 32768)");

	// Plausible sides, but more pixels than the bytes that follow.
	auto longer = bytes;
	const std::uint32_t cols = 2000;
	std::memcpy(longer.data() + at + 4, &cols, 4);
	const auto why = check(longer);
	EXPECT_NE(why.find("range image of 2000 x 30 pixels needs 120000 bytes, more than the"), std::string::npos) << why;

	// A damaged 3D point count.
	auto withPoints = serialize(*observation(50));
	const std::uint32_t fifty = 50;
	std::size_t n = 0;
	while (n + 4 <= withPoints.size() && std::memcmp(withPoints.data() + n, &fifty, 4) != 0) n++;
	ASSERT_LT(n, withPoints.size());
	withPoints[n + 3] = 0x40;
	EXPECT_NE(check(withPoints).find("declares 1073741874 3D points"), std::string::npos) << check(withPoints);

	// The same damage inside a sensory frame.
	mrpt::obs::CSensoryFrame sf;
	sf.insert(observation(0));
	auto sfBytes = serialize(sf);
	sfBytes[rowsColsOffset(sfBytes) + 7] = 0x7f;
	EXPECT_NE(check(sfBytes).find("a side over 32768"), std::string::npos);
}

TEST(RawlogEntryCheck, ATruncatedEntryIsNamed)
{
	// The file ending inside an entry is said by the check (MRPT, reading on, could take what
	// follows a damaged gzip stream for the rest of the entry); every byte read is kept.
	const auto bytes = serialize(*observation(0));
	for (const std::size_t cut : {std::size_t{1}, std::size_t{20}, std::size_t{100}, rowsColsOffset(bytes) + 6, bytes.size() - 2})
	{
		const std::vector<std::uint8_t> part(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(cut));
		std::vector<std::uint8_t> consumed;
		EXPECT_EQ(check(part, &consumed), "the file ends inside it (" + std::to_string(cut) + " bytes read)") << cut;
		EXPECT_EQ(consumed, part) << "every byte read is kept for the replay, cut " << cut;
	}
	// Nothing left at all: the end of the file, not a damage.
	EXPECT_EQ(check({}), "");
}

TEST(RawlogEntryCheck, ADamagedCountClaimsNoMoreMemoryThanTheDataThere)
{
	// A gzip rawlog has no known size (bytesLeft unbounded): a point count of 2^30 must not
	// make the check allocate 16 GiB; it reads what is there and stops.
	auto bytes = serialize(*observation(50));
	const std::uint32_t fifty = 50;
	std::size_t n = 0;
	while (n + 4 <= bytes.size() && std::memcmp(bytes.data() + n, &fifty, 4) != 0) n++;
	ASSERT_LT(n, bytes.size());
	bytes[n + 3] = 0x40;
	{
		// Over the point bound: named.
		mrpt::io::CMemoryStream in;
		in.assignMemoryNotOwn(bytes.data(), bytes.size());
		std::vector<std::uint8_t> head;
		EXPECT_EQ(checkRawlogEntry(in, head, RawlogEntryLimits{}), "CObservation3DRangeScan declares 1073741874 3D points (more than 67108864)");
	}
	// Without the bound: the check reads what is there, and finds the data end inside the entry.
	mrpt::io::CMemoryStream in;
	in.assignMemoryNotOwn(bytes.data(), bytes.size());
	std::vector<std::uint8_t> head;
	RawlogEntryLimits unbounded;
	unbounded.maxPoints = UINT64_MAX;
	EXPECT_EQ(checkRawlogEntry(in, head, unbounded), "the file ends inside it (" + std::to_string(bytes.size()) + " bytes read)");
	EXPECT_EQ(head.size(), bytes.size());
	EXPECT_LE(head.capacity(), 2 * bytes.size() + (std::size_t{1} << 21));
}

TEST(RawlogEntryCheck, ADamagedSensorPoseClassNameIsWalkedPastAsMrptReadsIt)
{
	// MRPT reads the sensor pose into an existing CPose3D without checking the class name: the
	// range image size after it must still be checked (found by fuzz_rawlog).
	auto bytes = serialize(*observation(0));
	const std::string name = "mrpt::poses::CPose3D";
	const auto it = std::search(bytes.begin(), bytes.end(), name.begin(), name.end());
	ASSERT_NE(it, bytes.end());
	*(it + 7) = 'w';  // "mrpt::pwses::CPose3D"
	bytes[rowsColsOffset(bytes) + 7] = 0x7f;
	EXPECT_NE(check(bytes).find("a side over 32768"), std::string::npos) << check(bytes);

	// MRPT finds the observation's class by the name after the last "::": a damaged namespace
	// still makes a CObservation3DRangeScan.
	bytes[7] = '[';  // "mrpt::o[s::CObservation3DRangeScan"
	EXPECT_NE(check(bytes).find("a side over 32768"), std::string::npos) << check(bytes);
}

TEST(RawlogEntryCheck, AColourImageStoredAsJpegMustDecode)
{
	// MRPT stores colour images raw unless JPEG compression is switched on.
	auto obs = observation(0);
	obs->hasIntensityImage = true;
	obs->intensityImage = mrpt::img::CImage(40, 30, mrpt::img::CH_RGB);
	for (int y = 0; y < 30; y++)
		for (int x = 0; x < 40; x++)
		{
			auto* p = obs->intensityImage.ptr<std::uint8_t>(x, y);
			p[0] = static_cast<std::uint8_t>(6 * x);
			p[1] = static_cast<std::uint8_t>(8 * y);
			p[2] = 90;
		}
	EXPECT_EQ(check(serialize(*obs)), "") << "raw colour pixels";
	const bool before = mrpt::img::CImage::DISABLE_JPEG_COMPRESSION();
	mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(false);
	const auto jpeg = serialize(*obs);
	mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(before);
	const std::uint8_t soi[3] = {0xFF, 0xD8, 0xFF};
	const auto at = std::search(jpeg.begin(), jpeg.end(), soi, soi + 3);
	ASSERT_NE(at, jpeg.end()) << "a JPEG inside the entry";
	EXPECT_EQ(check(jpeg), "");

	// Not a JPEG any more: libjpeg would end the process; the check names it.
	auto damaged = jpeg;
	damaged[static_cast<std::size_t>(at - jpeg.begin())] = 0x14;
	EXPECT_NE(check(damaged).find("intensity image: its "), std::string::npos) << check(damaged);
	EXPECT_NE(check(damaged).find("bytes of JPEG data do not decode"), std::string::npos);
}

TEST(RawlogEntryCheck, TheTailOfTheEntryIsWalkedToo)
{
	// An extra range image layer (version 10) with a damaged size: MRPT would write through a
	// null allocation (found by fuzz_rawlog). And a sensor label of 4 GiB.
	auto obs = observation(0);
	obs->sensorLabel = "KINECT";
	auto& layer = obs->rangeImageOtherLayers["ir"];
	layer.resize(30, 40);
	layer.fill(7);
	const auto bytes = serialize(*obs);
	EXPECT_EQ(check(bytes), "");
	const std::string name = "ir";
	const auto it = std::search(bytes.begin(), bytes.end(), name.begin(), name.end());
	ASSERT_NE(it, bytes.end());
	auto damaged = bytes;
	damaged[static_cast<std::size_t>(it - bytes.begin()) + 2 + 3] = 0x7f;  // rows' high byte
	EXPECT_NE(check(damaged).find("range image layer of"), std::string::npos) << check(damaged);

	const std::string label = "KINECT";
	const auto at = std::search(bytes.begin(), bytes.end(), label.begin(), label.end());
	ASSERT_NE(at, bytes.end());
	auto longLabel = bytes;
	longLabel[static_cast<std::size_t>(at - bytes.begin()) - 1] = 0xff;  // the length's high byte
	EXPECT_NE(check(longLabel).find("sensor label of"), std::string::npos) << check(longLabel);
}

TEST(RawlogEntryCheck, FlagsMustBeBooleans)
{
	// MRPT reads a flag byte into a bool unchecked: 20 would be undefined behaviour downstream
	// (found by fuzz_rawlog).
	auto bytes = serialize(*observation(0));
	bytes[rowsColsOffset(bytes) - 5] = 20;  // hasRangeImage, before the float rangeUnits
	EXPECT_EQ(check(bytes), "CObservation3DRangeScan hasRangeImage is 20, not a boolean (0 or 1)");
}

TEST(RawlogEntryCheck, AnImageEntryOfItsOwnHasItsJpegDecodedToo)
{
	// A rawlog entry that is a CImage (skipped by the frame source, but MRPT decodes it first).
	mrpt::img::CImage img(40, 30, mrpt::img::CH_RGB);
	img.filledRectangle(0, 0, 39, 29, mrpt::img::TColor(200, 100, 50));
	const bool before = mrpt::img::CImage::DISABLE_JPEG_COMPRESSION();
	mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(false);
	auto bytes = serialize(img);
	mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(before);
	EXPECT_EQ(check(bytes), "");
	const std::uint8_t soi[2] = {0xFF, 0xD8};
	const auto at = std::search(bytes.begin(), bytes.end(), soi, soi + 2);
	ASSERT_NE(at, bytes.end());
	*at = 0x58;
	EXPECT_NE(check(bytes).find("CImage entry: its "), std::string::npos) << check(bytes);
}

TEST(RawlogEntryCheck, AnImageObservationIsWalkedAndItsJpegDecoded)
{
	// The monocular input's entry: walked to its end, at the top level and in a sensory frame;
	// a damaged JPEG image or sensor label is named.
	auto obs = mrpt::obs::CObservationImage::Create();
	obs->image = mrpt::img::CImage(40, 30, mrpt::img::CH_RGB);
	obs->image.filledRectangle(0, 0, 39, 29, mrpt::img::TColor(30, 160, 90));
	obs->cameraParams.setIntrinsicParamsFromValues(50, 50, 19.5, 14.5);
	obs->sensorLabel = "CAMERA";
	const auto raw = serialize(*obs);
	std::vector<std::uint8_t> head;
	EXPECT_EQ(check(raw, &head), "");
	EXPECT_EQ(head.size(), raw.size() - 1) << "walked to the entry's end byte";
	mrpt::obs::CSensoryFrame sf;
	sf.insert(obs);
	EXPECT_EQ(check(serialize(sf)), "");

	// The label is its uint32 length (6, little-endian) and "CAMERA": make the length 2^31 + 6.
	auto longLabel = raw;
	const std::uint8_t label[10] = {6, 0, 0, 0, 'C', 'A', 'M', 'E', 'R', 'A'};
	const auto labelAt = std::search(longLabel.begin(), longLabel.end(), label, label + 10);
	ASSERT_NE(labelAt, longLabel.end());
	labelAt[3] = 0x80;
	EXPECT_NE(check(longLabel).find("CObservationImage sensor label of "), std::string::npos) << check(longLabel);

	const bool before = mrpt::img::CImage::DISABLE_JPEG_COMPRESSION();
	mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(false);
	auto jpeg = serialize(*obs);
	mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(before);
	EXPECT_EQ(check(jpeg), "");
	const std::uint8_t soi[3] = {0xFF, 0xD8, 0xFF};
	const auto at = std::search(jpeg.begin(), jpeg.end(), soi, soi + 3);
	ASSERT_NE(at, jpeg.end()) << "a JPEG inside the entry";
	*at = 0x14;
	EXPECT_NE(check(jpeg).find("CObservationImage image: its "), std::string::npos) << check(jpeg);
}
