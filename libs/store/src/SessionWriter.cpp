#include <keygrid/store/SessionWriter.h>

#include <chrono>
#include <stdexcept>

namespace keygrid::store
{
namespace
{
double secondsSince(std::chrono::steady_clock::time_point t0)
{
	return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

SessionWriter::SessionWriter(SessionStore store, const SessionWriterOptions& opts)
	: m_store(std::move(store)), m_path(m_store.path()), m_opts(opts), m_codec(opts.images), m_queue(opts.queueCapacity)
{
	if (m_store.mode() != SessionStore::Mode::ReadWrite)
		throw std::invalid_argument("SessionWriter: '" + m_path + "' was opened read-only");
	if (opts.queueCapacity == 0) throw std::invalid_argument("SessionWriter: queueCapacity must be >= 1, got 0");
	if (m_opts.threaded) m_thread = std::thread([this] { run(); });
}

SessionWriter::~SessionWriter()
{
	m_queue.close();
	if (m_thread.joinable()) m_thread.join();
}

void SessionWriter::process(SessionWriteJob& job)
{
	auto& u = job.update;
	const auto t0 = std::chrono::steady_clock::now();
	const std::size_t n = std::min(job.images.size(), u.keyframes.size());
	if (u.images.size() < n) u.images.resize(n);
	for (std::size_t i = 0; i < n; i++)
	{
		if (!u.images[i].empty()) continue;
		const auto& src = job.images[i];
		const cv::Mat raw = src.depth.type() == CV_32FC1 ? KeyFrameImageCodec::depthToRaw(src.depth, src.depthUnits) : src.depth;
		u.images[i] = m_codec.encode(src.colour, raw);
	}
	const double encodeSeconds = secondsSince(t0);
	const auto t1 = std::chrono::steady_clock::now();
	m_store.write(u);
	const double writeSeconds = secondsSince(t1);
	std::lock_guard<std::mutex> lk(m_mutex);
	m_stats.committed++;
	m_stats.encodeSeconds += encodeSeconds;
	m_stats.writeSeconds += writeSeconds;
}

void SessionWriter::run()
{
	while (auto job = m_queue.pop())
	{
		bool failed = false;
		{
			std::lock_guard<std::mutex> lk(m_mutex);
			failed = m_error != nullptr;
		}
		// After a failure nothing more is written (later updates may depend on the lost one).
		if (!failed)
		{
			try
			{
				process(*job);
			}
			catch (...)
			{
				std::lock_guard<std::mutex> lk(m_mutex);
				m_error = std::current_exception();
			}
		}
		std::lock_guard<std::mutex> lk(m_mutex);
		m_done++;
		m_progress.notify_all();
	}
}

void SessionWriter::rethrowError()
{
	std::exception_ptr e;
	{
		std::lock_guard<std::mutex> lk(m_mutex);
		e = m_error;
	}
	if (!e) return;
	try
	{
		std::rethrow_exception(e);
	}
	catch (const std::exception& ex)
	{
		throw std::runtime_error("SessionWriter: writing '" + m_path + "' failed: " + ex.what());
	}
}

void SessionWriter::submit(SessionWriteJob job)
{
	if (m_closed) throw std::logic_error("SessionWriter::submit: the writer of '" + m_path + "' was closed");
	rethrowError();
	if (!m_opts.threaded)
	{
		try
		{
			process(job);
		}
		catch (...)
		{
			std::lock_guard<std::mutex> lk(m_mutex);
			m_error = std::current_exception();
		}
		rethrowError();
		return;
	}
	{
		std::lock_guard<std::mutex> lk(m_mutex);
		m_submitted++;
	}
	m_queue.push(std::move(job));
}

void SessionWriter::flush()
{
	{
		std::unique_lock<std::mutex> lk(m_mutex);
		m_progress.wait(lk, [&] { return m_done == m_submitted; });
	}
	rethrowError();
}

void SessionWriter::close()
{
	if (m_closed) return;
	flush();
	m_closed = true;
	m_queue.close();
	if (m_thread.joinable()) m_thread.join();
}

SessionWriterStats SessionWriter::stats() const
{
	std::lock_guard<std::mutex> lk(m_mutex);
	return m_stats;
}

}  // namespace keygrid::store
