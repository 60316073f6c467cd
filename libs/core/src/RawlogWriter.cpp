#include <keygrid/core/RawlogWriter.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace keygrid::core
{
struct RawlogWriter::Impl
{
	/** The last serialized observation. It must outlive `out`: when a write fails (disk full),
	 * zlib keeps pointing at the input it could not compress, and gzclose() compresses it
	 * again. Written from the observation's own image buffers, that read freed memory once the
	 * caller had dropped the observation (found by AddressSanitizer with a full disk). */
	mrpt::io::CMemoryStream chunk;
	mrpt::io::CFileGZOutputStream out;
	bool failed{false};
};

RawlogWriter::RawlogWriter(const std::string& path, const RawlogWriterOptions& opts)
	: m_impl(std::make_unique<Impl>()), m_path(path), m_tmpPath(path + ".tmp"), m_opts(opts)
{
	// Before any frame is converted: a folder cannot take the rawlog's name at the end.
	if (std::filesystem::is_directory(path)) throw std::runtime_error("output '" + path + "' is a folder, not a file");
	const std::string dir = mrpt::system::extractFileDirectory(path);
	if (!dir.empty() && !mrpt::system::directoryExists(dir))
		throw std::runtime_error("output folder '" + dir + "' does not exist");
	if (!m_impl->out.open(m_tmpPath, opts.compressionLevel))
		throw std::runtime_error("cannot write '" + m_tmpPath + "'");
	const std::filesystem::path p(path);
	m_imagesDir = (p.parent_path() / (p.stem().string() + "_Images")).string();
}

RawlogWriter::~RawlogWriter()
{
	if (m_impl && m_impl->out.is_open())
	{
		m_impl->out.close();
		std::remove(m_tmpPath.c_str());
	}
}

void RawlogWriter::write(const mrpt::obs::CObservation::Ptr& obs)
{
	if (m_opts.externalImages)
		if (auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(obs);
			o && o->hasIntensityImage && !o->intensityImage.isExternallyStored())
		{
			if (!mrpt::system::directoryExists(m_imagesDir) &&
				!mrpt::system::createDirectory(m_imagesDir))
				throw std::runtime_error("cannot create '" + m_imagesDir + "'");
			char name[64];
			std::snprintf(name, sizeof(name), "rgb_%06zu.png", m_count);
			const std::string full = m_imagesDir + "/" + name;
			if (!o->intensityImage.saveToFile(full))
				throw std::runtime_error("cannot write '" + full + "'");
			o->intensityImage.setExternalStorage(name);  // relative to the images dir
		}
	// After a failed write zlib refers to `chunk` until close(): it must not change any more.
	if (m_impl->failed) throw std::runtime_error("cannot write '" + m_tmpPath + "' (an earlier write failed)");
	m_impl->chunk.clear();
	auto arch = mrpt::serialization::archiveFrom(m_impl->chunk);
	arch << *obs;
	const auto n = static_cast<size_t>(m_impl->chunk.getTotalBytesCount());
	if (m_impl->out.Write(m_impl->chunk.getRawBufferData(), n) != n)
	{
		m_impl->failed = true;
		throw std::runtime_error("cannot write '" + m_tmpPath + "' (disk full?)");
	}
	++m_count;
}

void RawlogWriter::close()
{
	if (m_impl->failed) throw std::runtime_error("cannot write '" + m_tmpPath + "' (an earlier write failed)");
	m_impl->out.close();
	if (std::rename(m_tmpPath.c_str(), m_path.c_str()) != 0)
		throw std::runtime_error("cannot rename '" + m_tmpPath + "' to '" + m_path + "'");
}

}  // namespace keygrid::core
