#include <keygrid/core/RawlogEntryCheck.h>

#include <algorithm>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <stdexcept>

namespace keygrid::core
{
namespace
{
/** Little-endian reads from a stream, recording every byte; nullopt on a short read. */
class Reader
{
   public:
	Reader(mrpt::io::CStream& in, std::vector<std::uint8_t>& consumed) : m_in(in), m_consumed(consumed) {}

	/** Reads `n` bytes in pieces of at most 1 MiB, so that a damaged count claims no more
	 * memory than the data that is really there. */
	bool bytes(std::size_t n)
	{
		constexpr std::size_t kPiece = std::size_t{1} << 20;
		for (std::size_t left = n; left > 0;)
		{
			const std::size_t want = std::min(left, kPiece), at = m_consumed.size();
			m_consumed.resize(at + want);
			const std::size_t got = m_in.Read(m_consumed.data() + at, want);
			m_consumed.resize(at + got);
			if (got != want) return false;
			left -= got;
		}
		return true;
	}
	template <typename T>
	std::optional<T> value()
	{
		if (!bytes(sizeof(T))) return std::nullopt;
		T v;
		std::memcpy(&v, m_consumed.data() + m_consumed.size() - sizeof(T), sizeof(T));
		return v;  // MRPT writes little-endian; keygrid builds for little-endian hosts only
	}
	/** An object header in MRPT 2's format: (0x80 | name length), class name, version. */
	std::optional<std::pair<std::string, std::uint8_t>> header()
	{
		const auto b = value<std::uint8_t>();
		if (!b || !(*b & 0x80)) return std::nullopt;  // older formats: not walked
		const std::size_t n = *b & 0x7F;
		if (!bytes(n)) return std::nullopt;
		std::string name(reinterpret_cast<const char*>(m_consumed.data() + m_consumed.size() - n), n);
		const auto version = value<std::uint8_t>();
		if (!version) return std::nullopt;
		return std::make_pair(name, *version);
	}
	std::size_t count() const { return m_consumed.size(); }
	const std::uint8_t* data() const { return m_consumed.data(); }

   private:
	mrpt::io::CStream& m_in;
	std::vector<std::uint8_t>& m_consumed;
};

/** Whether a serialized class name names `cls`: MRPT looks classes up by the part after the
 * last "::" (it reads names written with and without namespace), so this does too. */
bool isClass(const std::string& name, const char* cls)
{
	const auto colon = name.rfind("::");
	return (colon == std::string::npos ? name : name.substr(colon + 2)) == cls;
}

/** Bytes still available after what `r` consumed, from the entry's own start `start`. */
std::uint64_t left(const RawlogEntryLimits& l, const Reader& r, std::size_t start)
{
	const std::uint64_t used = r.count() - start;
	return l.bytesLeft > used ? l.bytesLeft - used : 0;
}

std::optional<std::string> checkRangeImage(Reader& r, const RawlogEntryLimits& l, std::size_t start);
std::optional<std::string> checkImage(Reader& r, const char* which, const RawlogEntryLimits& l, std::size_t start);

// CObservation3DRangeScan (versions 9, 10) up to its images:
//   float maxRange, CPose3D sensorPose (an object: header, 12 or 7 doubles, end byte 0x88),
//   bool hasPoints3D [uint32 N, 3 x N float, 2 x N uint16], bool hasRangeImage,
//   float rangeUnits [uint32 rows, uint32 cols, rows x cols uint16],
//   bool hasIntensityImage [CImage], bool hasConfidenceImage [CImage], ... (not walked further).
std::string checkRangeScan(Reader& r, std::uint8_t version, const RawlogEntryLimits& l, std::size_t start)
{
	if (version < 9 || version > 10) return {};
	if (!r.value<float>()) return {};
	// The sensor pose is read into an existing CPose3D: MRPT does not check the class name, so
	// neither does this walk. Version 3: translation + rotation matrix (12 doubles), 2:
	// translation + quaternion (7); older ones nest a matrix object (not walked).
	const auto pose = r.header();
	if (!pose || (pose->second != 2 && pose->second != 3)) return {};
	if (!r.bytes((pose->second == 3 ? 12 : 7) * sizeof(double))) return {};
	const auto end = r.value<std::uint8_t>();
	if (!end || *end != 0x88) return {};
	const auto hasPoints = r.value<std::uint8_t>();
	if (!hasPoints) return {};
	if (*hasPoints)
	{
		const auto n = r.value<std::uint32_t>();
		if (!n) return {};
		const std::uint64_t bytes = std::uint64_t{*n} * (3 * sizeof(float) + 2 * sizeof(std::uint16_t));
		if (*n > l.maxPoints)
			return "CObservation3DRangeScan declares " + std::to_string(*n) + " 3D points (more than " + std::to_string(l.maxPoints) + ")";
		if (bytes > left(l, r, start))
			return "CObservation3DRangeScan declares " + std::to_string(*n) + " 3D points (" + std::to_string(bytes) +
				   " bytes), more than the " + std::to_string(left(l, r, start)) + " bytes left in the file";
		if (!r.bytes(static_cast<std::size_t>(bytes))) return {};
	}
	const auto hasRange = r.value<std::uint8_t>();
	if (!hasRange || !r.value<float>()) return {};
	if (*hasRange)
	{
		const auto why = checkRangeImage(r, l, start);
		if (!why || !why->empty()) return why.value_or("");
	}
	// The intensity image, then the confidence image: walked while their layout is known.
	for (const char* which : {"intensity", "confidence"})
	{
		const auto has = r.value<std::uint8_t>();
		if (!has) return {};
		if (!*has) continue;
		const auto why = checkImage(r, which, l, start);
		if (!why || !why->empty()) return why.value_or("");
	}
	return {};
}

/** The range image size and data: nullopt (stop walking), "" (walked past it) or the damage. */
std::optional<std::string> checkRangeImage(Reader& r, const RawlogEntryLimits& l, std::size_t start)
{
	const auto rows = r.value<std::uint32_t>();
	const auto cols = rows ? r.value<std::uint32_t>() : std::nullopt;
	if (!rows || !cols) return std::nullopt;
	const std::string size = std::to_string(*cols) + " x " + std::to_string(*rows);
	if (*rows > l.maxImageSide || *cols > l.maxImageSide)
		return "CObservation3DRangeScan range image of " + size + " pixels (a side over " + std::to_string(l.maxImageSide) + ")";
	const std::uint64_t pixels = std::uint64_t{*rows} * *cols, bytes = pixels * sizeof(std::uint16_t);
	if (pixels > l.maxImagePixels)
		return "CObservation3DRangeScan range image of " + size + " pixels (more than " + std::to_string(l.maxImagePixels) + ")";
	if (bytes > left(l, r, start))
		return "CObservation3DRangeScan range image of " + size + " pixels needs " + std::to_string(bytes) +
			   " bytes, more than the " + std::to_string(left(l, r, start)) + " bytes left in the file";
	if (!r.bytes(static_cast<std::size_t>(bytes))) return std::nullopt;
	return std::string();
}

// A CImage (versions 7 to 9; MRPT 2.5 writes 9): bool external [string file name] | bool colour,
// then for colour int32 width, height: both >= 1, a JPEG (uint32 n, n bytes); both < 0, raw
// pixels (|width| x |height| x 3 bytes). MRPT hands the JPEG to libjpeg with its default error
// handler, which ends the process (exit(), no exception) on a damaged stream: the JPEG is
// decoded here first, by OpenCV, whose libjpeg error handler returns an error instead.
// Returns nullopt (stop walking), "" (walked past it) or the damage.
std::optional<std::string> checkImage(Reader& r, const char* which, const RawlogEntryLimits& l, std::size_t start)
{
	const auto h = r.header();
	if (!h || h->second < 7 || h->second > 9) return std::nullopt;
	const auto external = r.value<std::uint8_t>();
	if (!external || *external) return std::nullopt;  // a file name: read later, by OpenCV
	const auto colour = r.value<std::uint8_t>();
	if (!colour || !*colour) return std::nullopt;  // grey: not walked
	const auto w = r.value<std::int32_t>();
	const auto hgt = w ? r.value<std::int32_t>() : std::nullopt;
	if (!w || !hgt) return std::nullopt;
	if (*w >= 1 && *hgt >= 1)
	{
		const auto n = r.value<std::uint32_t>();
		if (!n) return std::nullopt;
		if (*n > left(l, r, start))
			return std::string("CObservation3DRangeScan ") + which + " image declares a JPEG of " + std::to_string(*n) +
				   " bytes, more than the " + std::to_string(left(l, r, start)) + " bytes left in the file";
		const std::size_t at = r.count();
		if (!r.bytes(*n)) return std::nullopt;
		const cv::Mat jpeg(1, static_cast<int>(*n), CV_8UC1, const_cast<std::uint8_t*>(r.data() + at));
		bool decodes = false;
		try
		{
			decodes = *n > 0 && !cv::imdecode(jpeg, cv::IMREAD_REDUCED_GRAYSCALE_8).empty();
		}
		catch (const cv::Exception&)
		{
		}
		if (!decodes)
			return std::string("CObservation3DRangeScan ") + which + " image: its " + std::to_string(*n) + " bytes of JPEG data do not decode";
		return std::string();
	}
	if (*w < 0 && *hgt < 0)
	{
		const std::uint64_t pixels = std::uint64_t(-std::int64_t{*w}) * std::uint64_t(-std::int64_t{*hgt});
		if (pixels > l.maxImagePixels || 3 * pixels > left(l, r, start))
			return std::string("CObservation3DRangeScan ") + which + " image of " + std::to_string(-std::int64_t{*w}) + " x " +
				   std::to_string(-std::int64_t{*hgt}) + " pixels does not fit in the file";
		if (!r.bytes(static_cast<std::size_t>(3 * pixels))) return std::nullopt;
		return std::string();
	}
	return std::nullopt;
}
}  // namespace

std::string checkRawlogEntry(mrpt::io::CStream& in, std::vector<std::uint8_t>& consumed, const RawlogEntryLimits& limits)
{
	Reader r(in, consumed);
	const std::size_t start = r.count();
	const auto h = r.header();
	if (!h) return {};
	if (isClass(h->first, "CObservation3DRangeScan")) return checkRangeScan(r, h->second, limits, start);
	// CSensoryFrame (version 2): uint32 count, then the observations as objects.
	if (isClass(h->first, "CSensoryFrame") && h->second == 2)
	{
		const auto n = r.value<std::uint32_t>();
		if (!n || *n == 0) return {};
		if (*n > left(limits, r, start))
			return "CSensoryFrame declares " + std::to_string(*n) + " observations, more than the " +
				   std::to_string(left(limits, r, start)) + " bytes left in the file";
		const auto first = r.header();
		if (first && isClass(first->first, "CObservation3DRangeScan"))
			return checkRangeScan(r, first->second, limits, start);
	}
	return {};
}

size_t PrefixedStream::Read(void* buf, size_t n)
{
	auto* out = static_cast<std::uint8_t*>(buf);
	const std::size_t fromPrefix = std::min(n, m_prefix.size() - m_offset);
	if (fromPrefix) std::memcpy(out, m_prefix.data() + m_offset, fromPrefix);
	m_offset += fromPrefix;
	return fromPrefix + (n > fromPrefix ? m_rest.Read(out + fromPrefix, n - fromPrefix) : 0);
}

size_t PrefixedStream::Write(const void*, size_t) { throw std::logic_error("PrefixedStream is read-only"); }

uint64_t PrefixedStream::Seek(int64_t, mrpt::io::CStream::TSeekOrigin)
{
	throw std::logic_error("PrefixedStream cannot seek");
}

}  // namespace keygrid::core
