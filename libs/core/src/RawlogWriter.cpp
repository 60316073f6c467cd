#include <keygrid/core/AtomicOutput.h>
#include <keygrid/core/RawlogWriter.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace keygrid::core
{
struct RawlogWriter::Impl
{
	std::unique_ptr<AtomicGzFile> out;
	mrpt::io::CMemoryStream chunk;  //!< one serialized observation, written in one piece
};

RawlogWriter::RawlogWriter(const std::string& path, const RawlogWriterOptions& opts)
	: m_impl(std::make_unique<Impl>()), m_path(path), m_opts(opts)
{
	// Before any frame is converted: a folder cannot take the rawlog's name at the end.
	if (std::filesystem::is_directory(path)) throw std::runtime_error("output '" + path + "' is a folder, not a file");
	const std::string dir = mrpt::system::extractFileDirectory(path);
	if (!dir.empty() && !mrpt::system::directoryExists(dir))
		throw std::runtime_error("output folder '" + dir + "' does not exist");
	m_impl->out = std::make_unique<AtomicGzFile>(path, opts.compressionLevel);
	const std::filesystem::path p(path);
	m_imagesDir = (p.parent_path() / (p.stem().string() + "_Images")).string();
}

RawlogWriter::~RawlogWriter() = default;  // an uncommitted AtomicGzFile removes its temporary file

void RawlogWriter::write(const mrpt::obs::CObservation::Ptr& obs)
{
	if (m_opts.externalImages)
	{
		mrpt::img::CImage* img = nullptr;
		if (auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(obs); o && o->hasIntensityImage)
			img = &o->intensityImage;
		else if (auto i = std::dynamic_pointer_cast<mrpt::obs::CObservationImage>(obs))
			img = &i->image;
		if (img && !img->isExternallyStored())
		{
			if (!mrpt::system::directoryExists(m_imagesDir) &&
				!mrpt::system::createDirectory(m_imagesDir))
				throw std::runtime_error("cannot create '" + m_imagesDir + "'");
			char name[64];
			std::snprintf(name, sizeof(name), "rgb_%06zu.png", m_count);
			const std::string full = m_imagesDir + "/" + name;
			writeFileThrough(full, [&](const std::string& tmp) { return img->saveToFile(tmp); });
			img->setExternalStorage(name);  // relative to the images dir
		}
	}
	if (!m_impl->out) throw std::logic_error("RawlogWriter: write after close");
	m_impl->chunk.clear();
	auto arch = mrpt::serialization::archiveFrom(m_impl->chunk);
	arch << *obs;
	m_impl->out->Write(m_impl->chunk.getRawBufferData(), static_cast<size_t>(m_impl->chunk.getTotalBytesCount()));
	++m_count;
}

void RawlogWriter::close()
{
	if (!m_impl->out) throw std::logic_error("RawlogWriter: closed twice");
	auto out = std::move(m_impl->out);
	out->commit();
}

}  // namespace keygrid::core
