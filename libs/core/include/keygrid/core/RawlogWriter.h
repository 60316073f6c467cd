#pragma once
/** \file RawlogWriter.h
 * Writes observations to an MRPT rawlog (observation-only format), atomically through an
 * AtomicGzFile: the data go to a temporary file renamed to `<path>` by close(), so a crash
 * never leaves a half file under the final name. A failed write (disk full) throws
 * std::runtime_error naming `<path>`; after it write() and close() throw too, and the
 * destructor removes the temporary file.
 */
#include <mrpt/obs/CObservation.h>

#include <memory>
#include <string>

namespace keygrid::core
{
struct RawlogWriterOptions
{
	/** gzip level 0-9 (Default: 1: most of the size gain, little time) */
	int compressionLevel{1};
	/** Store intensity images (CObservation3DRangeScan) and images (CObservationImage) as
	 * external PNG files in `<name>_Images/` instead of inside the rawlog, the layout
	 * rawlog-grabber uses (Default: false) */
	bool externalImages{false};
};

class RawlogWriter
{
   public:
	RawlogWriter(const std::string& path, const RawlogWriterOptions& opts = {});
	~RawlogWriter();  //!< discards the temp file if close() was not called

	/** Appends one observation (its intensity image is externalised when so configured).
	 * Throws std::runtime_error when the data cannot be written. */
	void write(const mrpt::obs::CObservation::Ptr& obs);
	/** Flushes and renames the temp file into place. Throws on I/O failure. */
	void close();

	std::size_t count() const { return m_count; }
	/** `<name>_Images` directory used for external images. */
	const std::string& imagesDir() const { return m_imagesDir; }

   private:
	struct Impl;
	std::unique_ptr<Impl> m_impl;
	std::string m_path, m_imagesDir;
	RawlogWriterOptions m_opts;
	std::size_t m_count{0};
};

}  // namespace keygrid::core
