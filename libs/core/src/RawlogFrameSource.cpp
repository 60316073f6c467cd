#include <keygrid/core/RawlogFrameSource.h>
#include <keygrid/core/RgbdObservation.h>
#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>

#include <deque>
#include <filesystem>
#include <stdexcept>

namespace keygrid::core
{
struct RawlogFrameSource::Impl
{
	mrpt::io::CFileGZInputStream file;
	std::deque<mrpt::obs::CObservation3DRangeScan::Ptr> pending;
	std::size_t entry{0};
	bool eof{false};
};

RawlogFrameSource::RawlogFrameSource(const std::string& path)
	: m_impl(std::make_unique<Impl>()), m_path(path)
{
	if (!mrpt::system::fileExists(path))
		throw std::runtime_error("rawlog '" + path + "' does not exist");
	if (!m_impl->file.open(path))
		throw std::runtime_error("cannot open rawlog '" + path + "'");
	m_fileSize = mrpt::system::getFileSize(path);
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

std::string RawlogFrameSource::describe() const { return "MRPT rawlog " + m_path; }

bool RawlogFrameSource::next(Frame& out)
{
	using namespace mrpt::obs;
	for (;;)
	{
		while (!m_impl->pending.empty())
		{
			auto obs = m_impl->pending.front();
			m_impl->pending.pop_front();
			try
			{
				obs->load();  // brings in externally stored images, if any
			}
			catch (const std::exception& e)
			{
				noteSkip(
					"rawlog entry " + std::to_string(m_impl->entry) +
					": cannot load external image: " + e.what());
				continue;
			}
			std::string why;
			if (!frameFromObservation(*obs, out, &why))
			{
				noteSkip("rawlog entry " + std::to_string(m_impl->entry) + ": " + why);
				continue;
			}
			obs->unload();
			out.index = m_nextIndex++;
			return true;
		}
		if (m_impl->eof) return false;

		CActionCollection::Ptr actions;
		CSensoryFrame::Ptr sf;
		CObservation::Ptr obs;
		std::size_t idx = m_impl->entry;
		bool ok = false;
		try
		{
			auto arch = mrpt::serialization::archiveFrom(m_impl->file);
			ok = CRawlog::getActionObservationPairOrObservation(arch, actions, sf, obs, idx);
		}
		catch (const std::exception& e)
		{
			m_impl->eof = true;
			throw std::runtime_error(
				"rawlog '" + m_path + "' is corrupt or truncated after entry " +
				std::to_string(m_impl->entry) + ": " + std::string(e.what()).substr(0, 300));
		}
		m_impl->entry++;
		if (!ok)
		{
			m_impl->eof = true;
			continue;
		}
		auto take = [&](const CObservation::Ptr& o) {
			if (auto s = std::dynamic_pointer_cast<CObservation3DRangeScan>(o))
				m_impl->pending.push_back(s);
		};
		if (obs) take(obs);
		if (sf)
			for (const auto& o : *sf) take(o);
	}
}

}  // namespace keygrid::core
