#include <keygrid/slam/ImageSpillFile.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

namespace keygrid::slam
{
namespace
{
std::string spillDir(const std::string& dir)
{
	if (!dir.empty()) return dir;
	const char* tmp = std::getenv("TMPDIR");
	return tmp && *tmp ? tmp : "/tmp";
}
}  // namespace

ImageSpillFile::ImageSpillFile(const std::string& dir)
{
	const std::string d = spillDir(dir);
	std::string path = d + "/keygrid-images-XXXXXX";
	std::vector<char> buf(path.begin(), path.end());
	buf.push_back('\0');
	m_fd = ::mkstemp(buf.data());
	if (m_fd < 0) throw std::runtime_error("cannot create an image spill file in '" + d + "': " + std::strerror(errno));
	// Unlinked now: the open descriptor keeps the data, nothing is left behind.
	::unlink(buf.data());
}

ImageSpillFile::~ImageSpillFile()
{
	if (m_fd >= 0) ::close(m_fd);
}

ImageSpillFile::Record ImageSpillFile::append(const cv::Mat& m)
{
	Record r;
	if (m.empty()) return r;
	const cv::Mat c = m.isContinuous() ? m : m.clone();
	const std::size_t bytes = c.total() * c.elemSize();
	std::lock_guard<std::mutex> lk(m_mutex);
	r.offset = m_end;
	r.rows = c.rows;
	r.cols = c.cols;
	r.type = c.type();
	const auto* p = c.ptr<const char>();
	std::size_t done = 0;
	while (done < bytes)
	{
		const ssize_t n = ::pwrite(m_fd, p + done, bytes - done, static_cast<off_t>(r.offset + done));
		if (n < 0 && errno == EINTR) continue;
		if (n <= 0) throw std::runtime_error(std::string("image spill file: write failed: ") + std::strerror(errno));
		done += static_cast<std::size_t>(n);
	}
	m_end += bytes;
	return r;
}

cv::Mat ImageSpillFile::read(const Record& r) const
{
	if (r.empty()) return {};
	cv::Mat m(r.rows, r.cols, r.type);
	const std::size_t bytes = m.total() * m.elemSize();
	auto* p = m.ptr<char>();
	std::size_t done = 0;
	while (done < bytes)
	{
		const ssize_t n = ::pread(m_fd, p + done, bytes - done, static_cast<off_t>(r.offset + done));
		if (n < 0 && errno == EINTR) continue;
		if (n <= 0) throw std::runtime_error(std::string("image spill file: read failed: ") + (n == 0 ? "unexpected end" : std::strerror(errno)));
		done += static_cast<std::size_t>(n);
	}
	return m;
}

std::uint64_t ImageSpillFile::size() const
{
	std::lock_guard<std::mutex> lk(m_mutex);
	return m_end;
}

}  // namespace keygrid::slam
