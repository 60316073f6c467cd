#include <keygrid/core/ImageObservation.h>
#include <keygrid/core/RawlogEntryCheck.h>
#include <keygrid/core/RawlogFrameSource.h>
#include <keygrid/core/RgbdObservation.h>
#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>

#include <deque>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace keygrid::core
{
namespace
{
/** One line out of a (nested, multi-line) MRPT exception text: its innermost "Message:". */
std::string innermostReason(const std::string& what)
{
	const auto m = what.rfind("Message:");
	std::string line = m == std::string::npos ? what : what.substr(m + 8);
	line = line.substr(0, line.find('\n'));
	const auto b = line.find_first_not_of(" \t");
	line = b == std::string::npos ? std::string() : line.substr(b);
	return line.size() > 300 ? line.substr(0, 300) : line;
}
}  // namespace

struct RawlogFrameSource::Impl
{
	mrpt::io::CFileGZInputStream file;
	std::deque<mrpt::obs::CObservation::Ptr> pending;  //!< CObservation3DRangeScan or CObservationImage
	std::size_t entry{0};
	bool eof{false};
};

RawlogFrameSource::RawlogFrameSource(const std::string& path, const FrameSourceOptions& opts)
	: m_impl(std::make_unique<Impl>()), m_path(path), m_depth(opts.depth), m_camera(opts.camera)
{
	if (!mrpt::system::fileExists(path))
		throw std::runtime_error("rawlog '" + path + "' does not exist");
	if (!m_impl->file.open(path))
		throw std::runtime_error("cannot open rawlog '" + path + "'");
	m_fileSize = mrpt::system::getFileSize(path);
	{
		std::ifstream magic(path, std::ios::binary);
		unsigned char b[2] = {0, 0};
		magic.read(reinterpret_cast<char*>(b), 2);
		m_compressed = b[0] == 0x1f && b[1] == 0x8b;
	}
	// External (lazy-load) images are stored relative to <name>_Images/ (rawlog-grabber and
	// RawlogWriter) or, in older rawlogs, Images/ beside the file.
	const std::filesystem::path p(path);
	const auto named = p.parent_path() / (p.stem().string() + "_Images");
	const auto plain = p.parent_path() / "Images";
	if (std::filesystem::is_directory(named))
		mrpt::img::CImage::setImagesPathBase(named.string());
	else if (std::filesystem::is_directory(plain))
		mrpt::img::CImage::setImagesPathBase(plain.string());
	else
		mrpt::img::CImage::setImagesPathBase(mrpt::obs::CRawlog::detectImagesDirectory(path));
}

RawlogFrameSource::~RawlogFrameSource() = default;

std::size_t RawlogFrameSource::bytesRead() const { return m_impl->file.getPosition(); }

std::string RawlogFrameSource::describe() const
{
	return "MRPT rawlog " + m_path + (m_depth == DepthUse::Ignore ? " (images only, depth ignored)" : "");
}

bool RawlogFrameSource::loadAndConvert(const mrpt::obs::CObservation& obs, Frame& out, std::string& why) const
{
	using namespace mrpt::obs;
	const std::string entry = "rawlog entry " + std::to_string(m_impl->entry - 1) + ": ";
	const auto* scan = dynamic_cast<const CObservation3DRangeScan*>(&obs);
	const auto* image = dynamic_cast<const CObservationImage*>(&obs);
	try
	{
		// Brings in externally stored images; without depth, the intensity image alone.
		if (scan && m_depth == DepthUse::Ignore)
			scan->intensityImage.forceLoad();
		else
			obs.load();
	}
	catch (const std::exception& e)
	{
		why = entry + "cannot load external image: " + e.what();
		return false;
	}
	bool ok = false;
	if (scan && m_depth == DepthUse::Use)
		ok = frameFromObservation(*scan, out, &why);
	else if (scan)
		ok = imageFrameFromObservation(*scan, out, &why);
	else if (image)
		ok = frameFromImageObservation(*image, out, m_camera, &why);
	obs.unload();
	if (!ok) why = entry + why;
	return ok;
}

bool RawlogFrameSource::next(Frame& out)
{
	using namespace mrpt::obs;
	for (;;)
	{
		while (!m_impl->pending.empty())
		{
			const auto obs = m_impl->pending.front();
			m_impl->pending.pop_front();
			std::string why;
			if (!loadAndConvert(*obs, out, why))
			{
				noteSkip(why);
				continue;
			}
			out.index = m_nextIndex++;
			return true;
		}
		if (m_impl->eof) return false;

		// Objects are read one by one rather than through CRawlog::getActionObservationPairOrObservation,
		// which reports a truncated or corrupt file as a normal end of file.
		mrpt::serialization::CSerializable::Ptr obj;
		const std::size_t posBefore = m_impl->file.getPosition();
		// The sizes the entry declares are checked before MRPT allocates from them
		// (RawlogEntryCheck.h); the bytes read for that are replayed to the deserializer.
		std::vector<std::uint8_t> head;
		RawlogEntryLimits limits;
		// Positions count uncompressed bytes; a gzip file inflates to at most 1032 times its size.
		const std::uint64_t size = m_compressed ? std::uint64_t{m_fileSize} * 1032 : m_fileSize;
		limits.bytesLeft = size > posBefore ? size - posBefore : 0;
		const std::string damaged = checkRawlogEntry(m_impl->file, head, limits);
		if (!damaged.empty())
		{
			m_impl->eof = true;
			throw std::runtime_error(
				"rawlog '" + m_path + "' is corrupt or truncated at entry " + std::to_string(m_impl->entry) + " (byte " +
				std::to_string(posBefore) + "): " + damaged);
		}
		try
		{
			PrefixedStream entry(head, m_impl->file);
			auto arch = mrpt::serialization::archiveFrom(entry);
			obj = arch.ReadObject();
		}
		catch (const mrpt::serialization::CExceptionEOF&)
		{
			m_impl->eof = true;
			// Nothing left: the end. Bytes left that do not make an object header: truncated.
			// (gzip rawlogs count positions in uncompressed bytes: no such check there.)
			if (m_compressed || posBefore >= m_fileSize) continue;
			throw std::runtime_error(
				"rawlog '" + m_path + "' is corrupt or truncated after entry " + std::to_string(m_impl->entry) +
				": incomplete object header at byte " + std::to_string(posBefore));
		}
		catch (const std::exception& e)
		{
			m_impl->eof = true;
			throw std::runtime_error(
				"rawlog '" + m_path + "' is corrupt or truncated after entry " +
				std::to_string(m_impl->entry) + ": " + innermostReason(e.what()));
		}
		m_impl->entry++;
		CSensoryFrame::Ptr sf = std::dynamic_pointer_cast<CSensoryFrame>(obj);
		CObservation::Ptr obs = std::dynamic_pointer_cast<CObservation>(obj);
		if (!sf && !obs && !std::dynamic_pointer_cast<CActionCollection>(obj))
			noteSkip(
				"rawlog entry " + std::to_string(m_impl->entry - 1) + ": unexpected object " +
				(obj ? std::string(obj->GetRuntimeClass()->className) : std::string("(null)")));
		// Other sensors' observations (a rawlog-grabber log may hold an IMU or a laser too) are
		// skipped and counted, so that a rawlog with no usable entry says why it gave no frame.
		auto take = [&](const CObservation::Ptr& o) {
			const bool usable = std::dynamic_pointer_cast<CObservation3DRangeScan>(o) ||
				(m_depth == DepthUse::Ignore && std::dynamic_pointer_cast<CObservationImage>(o));
			if (usable)
				m_impl->pending.push_back(o);
			else if (o)
				noteSkip(
					"rawlog entry " + std::to_string(m_impl->entry - 1) + ": " + o->GetRuntimeClass()->className +
					(m_depth == DepthUse::Use ? " is not an RGB-D observation" : " is not an image observation"));
		};
		if (obs) take(obs);
		if (sf)
			for (const auto& o : *sf) take(o);
	}
}

}  // namespace keygrid::core
