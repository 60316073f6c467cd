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
			m_consumed.resize(at + std::min(got, want));
			if (got != want)
			{
				m_ended = true;
				return false;
			}
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
	/** Whether a read came back short: the stream ends (or its data is damaged) there. */
	bool ended() const { return m_ended; }
	const std::uint8_t* data() const { return m_consumed.data(); }

   private:
	mrpt::io::CStream& m_in;
	std::vector<std::uint8_t>& m_consumed;
	bool m_ended{false};
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

/** One step of the walk: nullopt stops it (a layout not walked, or a short read: the
 * deserializer reports the rest), "" walked past the part, any other text is the damage. */
using Step = std::optional<std::string>;
const Step kWalked = std::string();
#define KEYGRID_WALK(step)                        \
	do                                            \
	{                                             \
		const Step s_ = (step);                   \
		if (!s_ || !s_->empty()) return s_;       \
	} while (false)

/** Walks a CObservation3DRangeScan in MRPT 2's serialization (versions 9 and 10):
 *   float maxRange, CPose3D sensorPose, bool hasPoints3D [uint32 N, 3 x N float, 2 x N uint16],
 *   bool hasRangeImage, float rangeUnits [uint32 rows, cols, rows x cols uint16],
 *   bool hasIntensityImage [CImage], bool hasConfidenceImage [CImage], TCamera cameraParams,
 *   TCamera cameraParamsIntensity, CPose3D relativePoseIntensityWRTDepth, float stdError,
 *   uint64 timestamp, string sensorLabel, bool + string (external points file), bool + string
 *   (external range file), bool rangeIsDepth, int8 intensityChannel, bool hasPixelLabels
 *   [not walked], version 10: uint8 layers x {string name, uint32 rows, cols, rows x cols uint16}.
 * Nested objects end with the byte 0x88; strings are a uint32 length and the characters. */
class EntryWalker
{
   public:
	/** `subject`: the class named in errors. */
	EntryWalker(Reader& r, const RawlogEntryLimits& l, std::size_t start, std::string subject = "CObservation3DRangeScan")
		: m_r(r), m_l(l), m_start(start), m_subject(std::move(subject))
	{
	}

	Step walk(std::uint8_t version)
	{
		if (version < 9 || version > 10) return std::nullopt;
		if (!m_r.value<float>()) return std::nullopt;
		KEYGRID_WALK(pose());
		bool has = false;
		KEYGRID_WALK(flag("hasPoints3D", has));
		if (has) KEYGRID_WALK(points());
		KEYGRID_WALK(flag("hasRangeImage", has));
		if (!m_r.value<float>()) return std::nullopt;
		if (has) KEYGRID_WALK(uint16Image("range image"));
		KEYGRID_WALK(flag("hasIntensityImage", has));
		if (has) KEYGRID_WALK(image("intensity"));
		KEYGRID_WALK(flag("hasConfidenceImage", has));
		if (has) KEYGRID_WALK(image("confidence"));
		KEYGRID_WALK(camera());
		KEYGRID_WALK(camera());
		KEYGRID_WALK(pose());
		if (!m_r.value<float>() || !m_r.value<std::uint64_t>()) return std::nullopt;
		KEYGRID_WALK(string("sensor label"));
		KEYGRID_WALK(flag("points3D external", has));
		KEYGRID_WALK(string("external 3D points file name"));
		KEYGRID_WALK(flag("rangeImage external", has));
		KEYGRID_WALK(string("external range image file name"));
		KEYGRID_WALK(flag("range_is_depth", has));
		if (!m_r.value<std::int8_t>()) return std::nullopt;
		KEYGRID_WALK(flag("has pixel labels", has));
		if (has || version < 10) return std::nullopt;  // pixel labels: not walked
		const auto layers = m_r.value<std::uint8_t>();
		if (!layers) return std::nullopt;
		for (int i = 0; i < *layers; i++)
		{
			KEYGRID_WALK(string("range image layer name"));
			KEYGRID_WALK(uint16Image("range image layer"));
		}
		return kWalked;
	}

	/** Walks a CObservationImage (version 4, MRPT 2.x): CPose3D cameraPose, TCamera
	 * cameraParams, CImage image, uint64 timestamp, string sensorLabel. Older versions nest
	 * matrix objects (not walked). */
	Step walkImageObservation(std::uint8_t version)
	{
		if (version != 4) return std::nullopt;
		KEYGRID_WALK(pose());
		KEYGRID_WALK(camera());
		KEYGRID_WALK(image(""));
		if (!m_r.value<std::uint64_t>()) return std::nullopt;
		KEYGRID_WALK(string("sensor label"));
		return kWalked;
	}

   private:
	std::uint64_t left() const { return core::left(m_l, m_r, m_start); }
	std::string tooLarge(const std::string& what, std::uint64_t bytes) const
	{
		return m_subject + " " + what + " needs " + std::to_string(bytes) + " bytes, more than the " + std::to_string(left()) +
			   " bytes left in the file";
	}
	/** A bool as MRPT writes it, one byte: 0 or 1. MRPT reads any other value into a bool
	 * unchecked (undefined behaviour when it is used). */
	Step flag(const char* what, bool& out)
	{
		const auto b = m_r.value<std::uint8_t>();
		if (!b) return std::nullopt;
		if (*b > 1) return m_subject + " " + std::string(what) + " is " + std::to_string(*b) + ", not a boolean (0 or 1)";
		out = *b == 1;
		return kWalked;
	}
	Step end()
	{
		const auto e = m_r.value<std::uint8_t>();
		return e && *e == 0x88 ? kWalked : Step();
	}
	/** A nested CPose3D, read into an existing object: MRPT does not check the class name, so
	 * neither does this walk. Version 3: translation + rotation matrix (12 doubles), 2:
	 * translation + quaternion (7); older ones nest a matrix object (not walked). */
	Step pose()
	{
		const auto h = m_r.header();
		if (!h || (h->second != 2 && h->second != 3)) return std::nullopt;
		if (!m_r.bytes((h->second == 3 ? 12 : 7) * sizeof(double))) return std::nullopt;
		return end();
	}
	/** A nested TCamera (versions 4 to 6): 13 doubles (focal length, 8 distortion, fx fy cx cy),
	 * uint32 nrows, ncols, [v5: string name], [v6: uint8 distortion model]. */
	Step camera()
	{
		const auto h = m_r.header();
		if (!h || h->second < 4 || h->second > 6) return std::nullopt;
		if (!m_r.bytes(13 * sizeof(double) + 2 * sizeof(std::uint32_t))) return std::nullopt;
		if (h->second >= 5) KEYGRID_WALK(string("camera name"));
		if (h->second >= 6 && !m_r.value<std::uint8_t>()) return std::nullopt;
		return end();
	}
	Step string(const char* what)
	{
		const auto n = m_r.value<std::uint32_t>();
		if (!n) return std::nullopt;
		if (*n > std::min<std::uint64_t>(left(), m_l.maxStringBytes))
			return m_subject + " " + std::string(what) + " of " + std::to_string(*n) + " bytes does not fit in the file";
		return m_r.bytes(*n) ? kWalked : Step();
	}
	Step points()
	{
		const auto n = m_r.value<std::uint32_t>();
		if (!n) return std::nullopt;
		if (*n > m_l.maxPoints)
			return "CObservation3DRangeScan declares " + std::to_string(*n) + " 3D points (more than " + std::to_string(m_l.maxPoints) + ")";
		const std::uint64_t bytes = std::uint64_t{*n} * (3 * sizeof(float) + 2 * sizeof(std::uint16_t));
		if (bytes > left())
			return "CObservation3DRangeScan declares " + std::to_string(*n) + " 3D points (" + std::to_string(bytes) +
				   " bytes), more than the " + std::to_string(left()) + " bytes left in the file";
		return m_r.bytes(static_cast<std::size_t>(bytes)) ? kWalked : Step();
	}
	/** uint32 rows, cols, then rows x cols uint16: the range image and its extra layers. */
	Step uint16Image(const std::string& what)
	{
		const auto rows = m_r.value<std::uint32_t>();
		const auto cols = rows ? m_r.value<std::uint32_t>() : std::nullopt;
		if (!rows || !cols) return std::nullopt;
		const std::string size = what + " of " + std::to_string(*cols) + " x " + std::to_string(*rows) + " pixels";
		if (*rows > m_l.maxImageSide || *cols > m_l.maxImageSide)
			return m_subject + " " + size + " (a side over " + std::to_string(m_l.maxImageSide) + ")";
		const std::uint64_t pixels = std::uint64_t{*rows} * *cols, bytes = pixels * sizeof(std::uint16_t);
		if (pixels > m_l.maxImagePixels)
			return m_subject + " " + size + " (more than " + std::to_string(m_l.maxImagePixels) + ")";
		if (bytes > left()) return tooLarge(size, bytes);
		return m_r.bytes(static_cast<std::size_t>(bytes)) ? kWalked : Step();
	}
	/** A nested CImage (MRPT 2.5 writes version 9). Versions 2 to 9: [v6: bool external [string
	 * file name]], bool colour; grey: int32 width, height, origin, imageSize, [v9: int32 depth],
	 * [v5: bool zip], raw bytes; colour, from v7: int32 width, height: both >= 1, a JPEG; both
	 * < 0, raw pixels (|width| x |height| x 3 bytes); colour before v7, and version 1: a JPEG
	 * (uint32 n, n bytes). MRPT hands a JPEG to libjpeg with its default error handler, which
	 * ends the process (exit(), no exception) on a damaged stream: it is decoded here first, by
	 * OpenCV, whose libjpeg error handler returns an error instead. */
	Step image(const std::string& which)
	{
		const auto h = m_r.header();
		if (!h) return std::nullopt;
		return imageBody(h->second, which.empty() ? "image" : which + " image");
	}

   public:
	/** A CImage after its header (version `v`), up to and with its end byte. */
	Step imageBody(std::uint8_t v, const std::string& what)
	{
		if (v == 0 || v > 9) return std::nullopt;  // v0: raw pixels, no JPEG
		if (v == 1)
		{
			KEYGRID_WALK(jpeg(what));
			return end();
		}
		bool yes = false;
		if (v >= 6)
		{
			KEYGRID_WALK(flag((what + " external").c_str(), yes));
			if (yes)
			{
				KEYGRID_WALK(string((what + " file name").c_str()));
				return end();
			}
		}
		KEYGRID_WALK(flag((what + " colour").c_str(), yes));
		if (!yes) KEYGRID_WALK(greyPixels(what, v));
		else if (v < 7) KEYGRID_WALK(jpeg(what));
		else KEYGRID_WALK(colourPixels(what));
		return end();
	}
   private:
	Step greyPixels(const std::string& what, std::uint8_t version)
	{
		if (!m_r.bytes(4 * sizeof(std::int32_t))) return std::nullopt;
		std::uint32_t imageSize = 0;
		std::memcpy(&imageSize, m_r.data() + m_r.count() - sizeof(std::int32_t), sizeof(imageSize));
		if (version >= 9 && !m_r.value<std::int32_t>()) return std::nullopt;
		bool zip = version == 3 || (version == 4 && imageSize > 16 * 1024);
		if (version >= 5) KEYGRID_WALK(flag((what + " zip").c_str(), zip));
		if (zip) return std::nullopt;  // MRPT refuses zip-compressed images itself
		if (imageSize > left()) return tooLarge(what, imageSize);
		return m_r.bytes(imageSize) ? kWalked : Step();
	}
	Step jpeg(const std::string& what)
	{
		const auto n = m_r.value<std::uint32_t>();
		if (!n) return std::nullopt;
		if (*n > left()) return tooLarge(what + " (JPEG)", *n);
		const std::size_t at = m_r.count();
		if (!m_r.bytes(*n)) return std::nullopt;
		bool decodes = false;
		try
		{
			const cv::Mat data(1, static_cast<int>(*n), CV_8UC1, const_cast<std::uint8_t*>(m_r.data() + at));
			decodes = *n > 0 && !cv::imdecode(data, cv::IMREAD_REDUCED_GRAYSCALE_8).empty();
		}
		catch (const cv::Exception&)
		{
		}
		if (!decodes) return m_subject + " " + what + ": its " + std::to_string(*n) + " bytes of JPEG data do not decode";
		return kWalked;
	}
	Step colourPixels(const std::string& what)
	{
		const auto w = m_r.value<std::int32_t>();
		const auto h = w ? m_r.value<std::int32_t>() : std::nullopt;
		if (!w || !h) return std::nullopt;
		if (*w >= 1 && *h >= 1) return jpeg(what);
		if (*w < 0 && *h < 0)
		{
			const std::uint64_t pixels = std::uint64_t(-std::int64_t{*w}) * std::uint64_t(-std::int64_t{*h});
			const std::string size = what + " of " + std::to_string(-std::int64_t{*w}) + " x " + std::to_string(-std::int64_t{*h}) + " pixels";
			if (pixels > m_l.maxImagePixels) return m_subject + " " + size + " (more than " + std::to_string(m_l.maxImagePixels) + ")";
			if (3 * pixels > left()) return tooLarge(size, 3 * pixels);
			return m_r.bytes(static_cast<std::size_t>(3 * pixels)) ? kWalked : Step();
		}
		return kWalked;  // an empty image: nothing follows
	}

	Reader& m_r;
	const RawlogEntryLimits& m_l;
	std::size_t m_start;
	std::string m_subject;
};
#undef KEYGRID_WALK

std::string checkRangeScan(Reader& r, std::uint8_t version, const RawlogEntryLimits& l, std::size_t start)
{
	return EntryWalker(r, l, start).walk(version).value_or("");
}
std::string checkImageObservation(Reader& r, std::uint8_t version, const RawlogEntryLimits& l, std::size_t start)
{
	return EntryWalker(r, l, start, "CObservationImage").walkImageObservation(version).value_or("");
}
std::string checkEntry(Reader& r, const RawlogEntryLimits& limits, std::size_t start)
{
	const auto h = r.header();
	if (!h) return {};
	if (isClass(h->first, "CObservation3DRangeScan")) return checkRangeScan(r, h->second, limits, start);
	if (isClass(h->first, "CObservationImage")) return checkImageObservation(r, h->second, limits, start);
	// An image on its own (not an observation, skipped later): its JPEG is decoded all the same.
	if (isClass(h->first, "CImage")) return EntryWalker(r, limits, start, "CImage").imageBody(h->second, "entry").value_or("");
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
		if (first && isClass(first->first, "CObservationImage"))
			return checkImageObservation(r, first->second, limits, start);
	}
	return {};
}
}  // namespace

std::string checkRawlogEntry(mrpt::io::CStream& in, std::vector<std::uint8_t>& consumed, const RawlogEntryLimits& limits)
{
	Reader r(in, consumed);
	const std::size_t start = r.count();
	std::string why = checkEntry(r, limits, start);
	// The data ended inside an entry the walk was reading: it is truncated (or its gzip stream
	// damaged). Said here rather than left to MRPT, which may read what follows differently.
	if (why.empty() && r.ended() && r.count() > start) why = "the file ends inside it (" + std::to_string(r.count() - start) + " bytes read)";
	return why;
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
