#pragma once
/** \file LiveFrameSource.h
 * Real-time decorator for a camera: a grab thread reads the inner source continuously and
 * keeps only the newest frame. A consumer slower than the camera receives the latest frame
 * each time it asks; the frames it had no time for are dropped and counted instead of
 * queueing up, so the latency stays at most one frame however slow tracking is.
 */
#include <keygrid/core/FrameSource.h>

#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>

namespace keygrid::slam
{
struct LiveFrameSourceOptions
{
	/** While next() waits for a frame it checks stopWhen this often [s] (Default: 0.05 s) */
	double pollPeriod{0.05};
	/** Polled while waiting: when it returns true next() returns false (Default: none) */
	std::function<bool()> stopWhen;
	/** Called by stop() to unblock an inner source waiting for the device (Default: none) */
	std::function<void()> cancelInner;
};

class LiveFrameSource : public core::FrameSource
{
   public:
	/** Starts grabbing from `inner` at once. */
	explicit LiveFrameSource(
		std::unique_ptr<core::FrameSource> inner, LiveFrameSourceOptions opts = {});
	/** Stops the grab thread and joins it. */
	~LiveFrameSource() override;

	/** The newest frame not returned yet; blocks until one arrives. Returns false when the
	 * inner source ended (after its last frame), after stop(), or when stopWhen() holds.
	 * Rethrows an error of the inner source once the frame grabbed before it was delivered. */
	bool next(core::Frame& out) override;
	std::optional<std::size_t> sizeHint() const override { return std::nullopt; }
	std::string describe() const override { return m_describe + " (live: newest frame only)"; }

	/** Ends the stream: the grab thread exits after its current read. Thread-safe. */
	void stop();

	/** Frames read from the inner source so far. */
	std::size_t grabbedCount() const { return m_grabbed.load(); }
	/** Frames replaced by a newer one before next() took them. */
	std::size_t droppedCount() const { return m_dropped.load(); }
	/** Entries the inner source skipped (bad observations), as last reported. */
	std::size_t innerSkipped() const { return m_innerSkipped.load(); }

   private:
	void grabLoop();

	std::unique_ptr<core::FrameSource> m_inner;
	LiveFrameSourceOptions m_opts;
	std::string m_describe;
	std::mutex m_mutex;
	std::condition_variable m_cv;
	core::Frame m_latest;  //!< guarded by m_mutex
	bool m_hasLatest{false};  //!< guarded by m_mutex
	bool m_ended{false};  //!< guarded by m_mutex: the grab thread finished
	std::string m_error;  //!< guarded by m_mutex: what the inner source threw
	std::atomic<bool> m_stop{false};
	std::atomic<std::size_t> m_grabbed{0}, m_dropped{0}, m_innerSkipped{0};
	std::thread m_thread;
};

}  // namespace keygrid::slam
