#pragma once
/** \file PrefetchingFrameSource.h
 * Decorator that reads (decodes) frames of another source ahead on a worker thread. Frames come
 * out in the same order with the same content, so results stay deterministic; only the I/O and
 * PNG decoding overlap with the caller's processing.
 */
#include <keygrid/core/BoundedQueue.h>
#include <keygrid/core/FrameSource.h>

#include <atomic>
#include <memory>
#include <mutex>
#include <thread>

namespace keygrid::core
{
class PrefetchingFrameSource : public FrameSource
{
   public:
	/** Takes ownership of `inner`; keeps at most `depth` decoded frames ahead. */
	PrefetchingFrameSource(std::unique_ptr<FrameSource> inner, std::size_t depth = 4);
	~PrefetchingFrameSource() override;

	/** Next frame; rethrows (on this thread) an error the worker met, after the frames
	 * decoded before it. */
	bool next(Frame& out) override;
	std::optional<std::size_t> sizeHint() const override { return m_sizeHint; }
	std::string describe() const override { return m_describe; }

	/** Seconds the worker spent inside the inner source's next() for the last frame returned. */
	double lastLoadSeconds() const { return m_lastLoad; }
	/** Skips seen by the inner source (valid once the stream ended). */
	std::size_t innerSkipped() const { return m_innerSkipped.load(); }
	/** Why the inner source skipped its latest skipped entry ("" if none). */
	std::string innerLastSkipReason() const
	{
		std::lock_guard<std::mutex> lk(m_skipMutex);
		return m_innerLastSkip;
	}

   private:
	struct Item
	{
		Frame frame;
		double seconds{0};
		std::string error;  //!< non-empty: the inner source threw
	};
	std::unique_ptr<FrameSource> m_inner;
	std::optional<std::size_t> m_sizeHint;
	std::string m_describe;
	BoundedQueue<Item> m_queue;
	std::thread m_worker;
	double m_lastLoad{0};
	std::atomic<std::size_t> m_innerSkipped{0};
	mutable std::mutex m_skipMutex;
	std::string m_innerLastSkip;  //!< guarded by m_skipMutex
};

}  // namespace keygrid::core
