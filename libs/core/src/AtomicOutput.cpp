#include <keygrid/core/AtomicOutput.h>
#include <mrpt/serialization/CArchive.h>
#include <zlib.h>

#include <cerrno>
#include <cstdio>
#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace keygrid::core
{
// The extension stays last: writers that take a file name (OpenCV, MRPT's CImage) choose the
// format by it.
std::string atomicTmpPath(const std::string& path)
{
	const std::filesystem::path p(path);
	return (p.parent_path() / (p.stem().string() + ".tmp" + p.extension().string())).string();
}

namespace
{
std::string errnoText(int e) { return e ? std::string(std::strerror(e)) : std::string("unknown error"); }

/** Gives the finished temporary file its final name; removes it when that fails. */
void renameIntoPlace(const std::string& tmp, const std::string& path)
{
	if (std::rename(tmp.c_str(), path.c_str()) != 0)
	{
		const int e = errno;
		std::remove(tmp.c_str());
		throw std::runtime_error("cannot rename '" + tmp + "' to '" + path + "': " + errnoText(e));
	}
}

/** Runs `produce(tmp)`, then renames tmp to path; removes tmp and names `path` on failure. */
void produceThenRename(const std::string& path, const std::function<void(const std::string&)>& produce)
{
	const std::string tmp = atomicTmpPath(path);
	try
	{
		if (std::filesystem::is_directory(path)) throw std::runtime_error("it is a folder");
		produce(tmp);
	}
	catch (const std::exception& e)
	{
		std::remove(tmp.c_str());
		throw std::runtime_error("cannot write '" + path + "': " + e.what());
	}
	renameIntoPlace(tmp, path);
}

}  // namespace

void writeFileAtomically(const std::string& path, const std::string& content)
{
	writeFileAtomically(path, [&](std::ostream& f) { f.write(content.data(), static_cast<std::streamsize>(content.size())); });
}

void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write)
{
	produceThenRename(path, [&](const std::string& tmp) {
		errno = 0;
		std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
		if (!f) throw std::runtime_error(errnoText(errno));
		write(f);
		f.flush();
		if (!f) throw std::runtime_error(errnoText(errno));
		f.close();
		if (f.fail()) throw std::runtime_error(errnoText(errno));
	});
}

void writeFileThrough(const std::string& path, const std::function<bool(const std::string& tmpPath)>& write)
{
	produceThenRename(path, [&](const std::string& tmp) {
		errno = 0;
		if (!write(tmp)) throw std::runtime_error(errno ? errnoText(errno) : "the writer failed");
		if (!std::filesystem::is_regular_file(tmp)) throw std::runtime_error("the writer produced no file");
	});
}

void writeGzAtomically(const std::string& path, const std::function<void(mrpt::io::CStream&)>& write, int level)
{
	AtomicGzFile f(path, level);
	write(f);
	f.commit();
}

AtomicGzFile::AtomicGzFile(const std::string& path, int level) : m_path(path), m_tmp(atomicTmpPath(path))
{
	if (level < 0 || level > 9) throw std::invalid_argument("AtomicGzFile: level must be in 0..9");
	if (std::filesystem::is_directory(path)) throw std::runtime_error("cannot write '" + path + "': it is a folder");
	errno = 0;
	m_gz = gzopen(m_tmp.c_str(), ("wb" + std::to_string(level)).c_str());
	if (!m_gz) throw std::runtime_error("cannot write '" + path + "': " + errnoText(errno));
}

AtomicGzFile::~AtomicGzFile()
{
	if (!m_gz) return;
	gzclose(static_cast<gzFile>(m_gz));
	std::remove(m_tmp.c_str());
}

size_t AtomicGzFile::Read(void*, size_t) { throw std::logic_error("AtomicGzFile is write-only"); }

uint64_t AtomicGzFile::Seek(int64_t, mrpt::io::CStream::TSeekOrigin) { throw std::logic_error("AtomicGzFile cannot seek"); }

size_t AtomicGzFile::Write(const void* buf, size_t n)
{
	if (!m_gz) throw std::logic_error("AtomicGzFile: write after commit");
	if (m_failed) throw std::runtime_error("cannot write '" + m_path + "' (an earlier write failed)");
	// zlib compresses from the staging buffer, never from the caller's memory: after a failed
	// write it keeps pointing at its input, and gzclose() reads it again, when the caller's
	// buffer may be gone.
	const auto* p = static_cast<const char*>(buf);
	for (size_t done = 0; done < n;)
	{
		const size_t chunk = std::min(n - done, kStagingBytes);
		m_staging.assign(p + done, p + done + chunk);
		errno = 0;
		const int w = gzwrite(static_cast<gzFile>(m_gz), m_staging.data(), static_cast<unsigned>(chunk));
		if (w <= 0 || static_cast<size_t>(w) != chunk)
		{
			m_failed = true;
			int zerr = 0;
			const char* msg = gzerror(static_cast<gzFile>(m_gz), &zerr);
			throw std::runtime_error(
				"cannot write '" + m_path + "': " + (zerr == Z_ERRNO ? errnoText(errno) : std::string(msg ? msg : "zlib error")));
		}
		done += chunk;
		m_written += chunk;
	}
	return n;
}

void AtomicGzFile::commit()
{
	if (!m_gz) throw std::logic_error("AtomicGzFile: committed twice");
	if (m_failed) throw std::runtime_error("cannot write '" + m_path + "' (an earlier write failed)");
	errno = 0;
	const int rc = gzclose(static_cast<gzFile>(m_gz));
	const int e = errno;
	m_gz = nullptr;
	if (rc != Z_OK)
	{
		std::remove(m_tmp.c_str());
		throw std::runtime_error("cannot write '" + m_path + "': " + (rc == Z_ERRNO ? errnoText(e) : "zlib error " + std::to_string(rc)));
	}
	renameIntoPlace(m_tmp, m_path);
}

void saveGzAtomically(const mrpt::serialization::CSerializable& obj, const std::string& path)
{
	writeGzAtomically(path, [&](mrpt::io::CStream& s) { mrpt::serialization::archiveFrom(s) << obj; });
}

}  // namespace keygrid::core
