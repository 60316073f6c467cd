#pragma once
/** \file ImageSpillFile.h
 * An append-only scratch file of raw image buffers (cv::Mat bytes as they are, so what comes
 * back is bit-identical). The file is created in a folder (default: $TMPDIR, else /tmp) and
 * unlinked at once: it lives as long as the object, and the system reclaims it also when the
 * process ends on an error or a signal.
 */
#include <opencv2/core.hpp>

#include <cstdint>
#include <mutex>
#include <string>

namespace keygrid::slam
{
class ImageSpillFile
{
   public:
	/** Where one image lies in the file. */
	struct Record
	{
		std::uint64_t offset{0};
		int rows{0}, cols{0}, type{0};
		bool empty() const { return rows == 0 || cols == 0; }
	};

	/** Creates the file in `dir` (empty: $TMPDIR, else /tmp). Throws std::runtime_error
	 * naming the folder when it cannot. */
	explicit ImageSpillFile(const std::string& dir = {});
	~ImageSpillFile();
	ImageSpillFile(const ImageSpillFile&) = delete;
	ImageSpillFile& operator=(const ImageSpillFile&) = delete;

	/** Appends the bytes of `m` (any type; empty gives an empty record). Thread-safe. */
	Record append(const cv::Mat& m);
	/** The image of `r`, a new buffer. Thread-safe. Throws std::runtime_error on a read error. */
	cv::Mat read(const Record& r) const;
	/** Bytes written so far. */
	std::uint64_t size() const;

   private:
	int m_fd{-1};
	std::uint64_t m_end{0};
	mutable std::mutex m_mutex;
};

}  // namespace keygrid::slam
