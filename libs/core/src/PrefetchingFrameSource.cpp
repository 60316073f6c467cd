#include <keygrid/core/PrefetchingFrameSource.h>

#include <chrono>
#include <stdexcept>

namespace keygrid::core
{
PrefetchingFrameSource::PrefetchingFrameSource(std::unique_ptr<FrameSource> inner, std::size_t depth)
	: m_inner(std::move(inner)), m_queue(depth)
{
	if (!m_inner) throw std::invalid_argument("PrefetchingFrameSource: no inner source");
	m_sizeHint = m_inner->sizeHint();
	m_describe = m_inner->describe();
	m_worker = std::thread([this] {
		for (;;)
		{
			Item it;
			const auto t0 = std::chrono::steady_clock::now();
			bool more = false;
			try
			{
				more = m_inner->next(it.frame);
			}
			catch (const std::exception& e)
			{
				it.error = e.what();
			}
			it.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
			if (m_inner->skippedCount() != m_innerSkipped.load())
			{
				std::lock_guard<std::mutex> lk(m_skipMutex);
				m_innerLastSkip = m_inner->lastSkipReason();
			}
			m_innerSkipped = m_inner->skippedCount();
			if (!more && it.error.empty()) break;
			const bool stop = !it.error.empty();
			if (!m_queue.push(std::move(it)) || stop) break;
		}
		m_queue.close();
	});
}

PrefetchingFrameSource::~PrefetchingFrameSource()
{
	m_queue.close();  // unblocks a worker waiting for space
	if (m_worker.joinable()) m_worker.join();
}

bool PrefetchingFrameSource::next(Frame& out)
{
	auto it = m_queue.pop();
	if (!it) return false;
	if (!it->error.empty()) throw std::runtime_error(it->error);
	out = std::move(it->frame);
	m_lastLoad = it->seconds;
	return true;
}

}  // namespace keygrid::core
