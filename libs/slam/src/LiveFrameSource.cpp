#include <keygrid/slam/LiveFrameSource.h>

#include <chrono>
#include <stdexcept>

namespace keygrid::slam
{
LiveFrameSource::LiveFrameSource(std::unique_ptr<core::FrameSource> inner, LiveFrameSourceOptions opts)
	: m_inner(std::move(inner)), m_opts(std::move(opts))
{
	if (!m_inner) throw std::invalid_argument("LiveFrameSource: no inner source");
	if (!(m_opts.pollPeriod > 0))
		throw std::invalid_argument("LiveFrameSource: pollPeriod = " + std::to_string(m_opts.pollPeriod) + " (must be > 0)");
	m_describe = m_inner->describe();
	m_thread = std::thread([this] { grabLoop(); });
}

LiveFrameSource::~LiveFrameSource()
{
	stop();
	if (m_thread.joinable()) m_thread.join();
}

void LiveFrameSource::stop()
{
	if (m_stop.exchange(true)) return;
	if (m_opts.cancelInner) m_opts.cancelInner();
	std::lock_guard<std::mutex> lk(m_mutex);
	m_cv.notify_all();
}

void LiveFrameSource::grabLoop()
{
	std::string error;
	try
	{
		while (!m_stop.load())
		{
			core::Frame f;
			if (!m_inner->next(f)) break;
			m_innerSkipped.store(m_inner->skippedCount());
			m_grabbed.fetch_add(1);
			std::lock_guard<std::mutex> lk(m_mutex);
			if (m_hasLatest) m_dropped.fetch_add(1);  // the consumer never saw it
			m_latest = std::move(f);
			m_hasLatest = true;
			m_cv.notify_all();
		}
	}
	catch (const std::exception& e)
	{
		error = e.what();
	}
	m_innerSkipped.store(m_inner->skippedCount());
	std::lock_guard<std::mutex> lk(m_mutex);
	m_ended = true;
	m_error = error;
	m_cv.notify_all();
}

bool LiveFrameSource::next(core::Frame& out)
{
	const auto period = std::chrono::duration<double>(m_opts.pollPeriod);
	std::unique_lock<std::mutex> lk(m_mutex);
	for (;;)
	{
		if (m_hasLatest)
		{
			out = std::move(m_latest);
			m_latest = core::Frame();
			m_hasLatest = false;
			return true;
		}
		if (m_ended)
		{
			if (!m_error.empty())
			{
				const std::string e = m_error;
				m_error.clear();  // report it once
				throw std::runtime_error(e);
			}
			return false;
		}
		if (m_stop.load()) return false;
		if (m_opts.stopWhen && m_opts.stopWhen())
		{
			lk.unlock();
			stop();
			return false;
		}
		m_cv.wait_for(lk, period);
	}
}

}  // namespace keygrid::slam
