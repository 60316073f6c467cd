#pragma once
/** \file RawlogEntryCheck.h
 * Checks the sizes a rawlog entry declares before MRPT deserializes it.
 *
 * MRPT trusts the row and column counts of a serialized CObservation3DRangeScan range image:
 * its matrix allocator returns null for a size it cannot allocate, and the read that follows
 * writes through it (a damaged byte in an entry's "cols" is a segfault, not an exception).
 * RawlogEntryCheck reads the head of the next object in MRPT's serialization format up to
 * the range image size, checks it, and hands the bytes it read back to the deserializer
 * through PrefixedStream, so the stream is read once.
 *
 * A colour image stored as JPEG inside the entry is decoded first too: MRPT hands it to
 * libjpeg with the default error handler, which ends the process (exit()) on a damaged stream.
 *
 * Walked: a CObservation3DRangeScan (serialization versions 9 and 10, MRPT 2.x) to its end (its
 * range image and extra layers, images, cameras, strings) and a CObservationImage (version 4:
 * pose, camera, image, label), at the top level or as the first observation of a
 * CSensoryFrame, and a CImage entry of its own. Any other object (other observation classes,
 * whose images are not decoded first), or a layout this walker does not know (pixel labels,
 * old pose versions), ends the walk there: the rest is passed on unchecked.
 */
#include <mrpt/io/CStream.h>

#include <cstdint>
#include <string>
#include <vector>

namespace keygrid::core
{
/** Bounds on what one rawlog entry may declare. */
struct RawlogEntryLimits
{
	/** Bytes left in the stream after the entry's first byte; an entry declaring more data
	 * than this is damaged. For a gzip rawlog (uncompressed size unknown): a bound such as
	 * 1032 times the file size, DEFLATE's largest ratio. */
	std::uint64_t bytesLeft{UINT64_MAX};
	/** Largest range image side: 32768 is far beyond any depth camera. */
	std::uint32_t maxImageSide{32768};
	/** Most range image pixels (8192 x 8192) and 3D points: what a damaged count may make
	 * MRPT allocate where bytesLeft is only a loose bound (gzip). */
	std::uint64_t maxImagePixels{std::uint64_t{1} << 26};
	std::uint64_t maxPoints{std::uint64_t{1} << 26};
	/** Longest string (sensor label, file names): 1 MiB. */
	std::uint64_t maxStringBytes{std::uint64_t{1} << 20};
};

/** Reads the head of the next serialized object from `in`, appending every byte read to
 * `consumed`, and returns an empty string when its declared sizes are plausible (or not
 * checked), else the reason in one line. Never throws on damaged data; a short read ends the
 * check (the deserializer then reports the truncation). */
std::string checkRawlogEntry(mrpt::io::CStream& in, std::vector<std::uint8_t>& consumed, const RawlogEntryLimits& limits);

/** A read-only stream that serves `prefix` first and then continues with `rest`: the bytes
 * checkRawlogEntry consumed, replayed to MRPT's deserializer. */
class PrefixedStream : public mrpt::io::CStream
{
   public:
	PrefixedStream(const std::vector<std::uint8_t>& prefix, mrpt::io::CStream& rest) : m_prefix(prefix), m_rest(rest) {}
	size_t Read(void* buf, size_t n) override;
	size_t Write(const void*, size_t) override;
	uint64_t Seek(int64_t, mrpt::io::CStream::TSeekOrigin) override;
	uint64_t getTotalBytesCount() const override { return m_rest.getTotalBytesCount(); }
	uint64_t getPosition() const override { return m_rest.getPosition() - (m_prefix.size() - m_offset); }

   private:
	const std::vector<std::uint8_t>& m_prefix;
	mrpt::io::CStream& m_rest;
	std::size_t m_offset{0};
};

}  // namespace keygrid::core
