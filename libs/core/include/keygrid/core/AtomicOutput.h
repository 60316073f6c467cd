#pragma once
/** \file AtomicOutput.h
 * The one way keygrid writes an output file: whole or not at all.
 *
 * Every writer here produces the file under a temporary name beside it (`<stem>.tmp<ext>`: writers that take a file name choose the format by its extension), checks
 * every write and the close (a full disk often shows only when buffered data is flushed at
 * close), and only then renames it to `path`. On any failure the temporary file is removed and
 * a std::runtime_error names `path` and the reason; a file that already had the name is left
 * as it was.
 */
#include <mrpt/io/CStream.h>
#include <mrpt/serialization/CSerializable.h>

#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

namespace keygrid::core
{
/** The temporary name `path` is written under: `<dir>/<stem>.tmp<ext>`. */
std::string atomicTmpPath(const std::string& path);

/** A gzip file written as a stream (an MRPT CStream, for CArchive): under atomicTmpPath(path)
 * until commit() checks the close and renames it. Every Write is checked and throws naming
 * `path`. Destroyed without commit() (an error, an interrupted run), the temporary file is
 * removed. The bytes equal mrpt::io::CFileGZOutputStream's at the same level. */
class AtomicGzFile : public mrpt::io::CStream
{
   public:
	explicit AtomicGzFile(const std::string& path, int level = 1);
	~AtomicGzFile() override;
	AtomicGzFile(const AtomicGzFile&) = delete;
	AtomicGzFile& operator=(const AtomicGzFile&) = delete;

	size_t Read(void*, size_t) override;
	size_t Write(const void* buf, size_t n) override;
	uint64_t Seek(int64_t, mrpt::io::CStream::TSeekOrigin) override;
	uint64_t getTotalBytesCount() const override { return m_written; }
	uint64_t getPosition() const override { return m_written; }
	/** Closes (checked) and renames the file to its final name. */
	void commit();
	const std::string& path() const { return m_path; }

   private:
	static constexpr size_t kStagingBytes = size_t{1} << 18;
	void* m_gz{nullptr};  //!< zlib gzFile
	std::string m_path, m_tmp;
	std::vector<char> m_staging;  //!< what zlib compresses from (see Write)
	uint64_t m_written{0};
	bool m_failed{false};
};

/** Writes `content` to `path`. */
void writeFileAtomically(const std::string& path, const std::string& content);

/** Writes what `write` puts into the stream (binary mode). */
void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write);

/** For writers that only take a file name (OpenCV, MRPT, OctoMap): `write(tmpPath)` produces
 * the file and returns false (or throws) on failure. A missing result also counts as failure. */
void writeFileThrough(const std::string& path, const std::function<bool(const std::string& tmpPath)>& write);

/** Writes a gzip file through an AtomicGzFile at zlib `level`. */
void writeGzAtomically(const std::string& path, const std::function<void(mrpt::io::CStream&)>& write, int level = 1);

/** Serializes `obj` (CArchive << obj) with writeGzAtomically: MRPT's *.bin, *.simplemap and
 * *.3Dscene files. */
void saveGzAtomically(const mrpt::serialization::CSerializable& obj, const std::string& path);

}  // namespace keygrid::core
