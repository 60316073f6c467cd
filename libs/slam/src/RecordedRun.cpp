#include <keygrid/slam/Interrupt.h>
#include <keygrid/slam/PlaybackSchedule.h>
#include <keygrid/slam/RecordedRun.h>
#include <keygrid/slam/System.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <thread>

namespace keygrid::slam
{
namespace
{
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/** Sleeps until `when`, in steps short enough to notice an interruption; false if one came. */
bool sleepUntil(Clock::time_point when)
{
	for (;;)
	{
		if (interruptRequested()) return false;
		const auto now = Clock::now();
		if (now >= when) return true;
		std::this_thread::sleep_for(std::min<Clock::duration>(when - now, std::chrono::milliseconds(50)));
	}
}
}  // namespace

/** A decoded frame with its features, and the time each took. */
struct RecordedFrameLoop::Extracted
{
	core::Frame frame;
	sfm::FrameFeatures features;
	double loadSeconds{0}, extractSeconds{0};
	/** When the frame was due for release (paced playback only): as a camera delivers it. */
	std::optional<Clock::time_point> released;
};

RecordedFrameLoop::RecordedFrameLoop(System& sys, core::PrefetchingFrameSource& source, const RecordedLoopOptions& opts)
	: m_sys(sys), m_source(source), m_opts(opts)
{
}

void RecordedFrameLoop::run(const std::function<void(const sfm::TrackedFrame&)>& onFrame)
{
	core::BoundedQueue<Extracted> queue(4);
	std::string producerError;
	std::thread producer([&] {
		try
		{
			produce(queue);
		}
		catch (const std::exception& ex)
		{
			producerError = ex.what();
		}
		queue.close();
	});
	try
	{
		consume(queue, onFrame);
	}
	catch (...)
	{
		queue.close();  // a joinable std::thread must not be destroyed
		producer.join();
		throw;
	}
	producer.join();
	if (!producerError.empty()) throw std::runtime_error(producerError);
}

void RecordedFrameLoop::produce(core::BoundedQueue<Extracted>& queue)
{
	core::Frame skippedFrame;
	for (std::size_t n = 0; n < m_opts.firstFrame && !interruptRequested(); n++)
		if (!m_source.next(skippedFrame)) break;
	const auto limitReached = [&](std::size_t n) { return m_opts.maxFrames && n >= m_opts.maxFrames; };
	std::optional<double> lastStamp;
	std::optional<PlaybackSchedule> schedule;
	if (m_opts.playbackRate > 0) schedule.emplace(m_opts.playbackRate);
	std::optional<Clock::time_point> firstRelease;
	for (std::size_t n = 0; !limitReached(n) && !interruptRequested();)
	{
		Extracted e;
		if (!m_source.next(e.frame)) break;
		if (!(e.frame.timestamp > 0) || (lastStamp && !(e.frame.timestamp > *lastStamp)))
		{
			char why[160];
			std::snprintf(why, sizeof(why), "frame %zu: timestamp %.6f %s", e.frame.index, e.frame.timestamp,
						  e.frame.timestamp > 0 ? "is not after the previous frame's" : "is missing");
			m_timestampSkips.count++;
			m_timestampSkips.last = why;
			continue;
		}
		lastStamp = e.frame.timestamp;
		if (schedule)
		{
			const double due = schedule->release(e.frame.timestamp);
			if (!firstRelease) firstRelease = Clock::now();
			const auto when = *firstRelease + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(due));
			if (!sleepUntil(when)) break;
			// A camera delivers the frame at its time even when the pipeline is behind (the
			// queue was full): latency counts from then.
			e.released = when;
		}
		n++;
		e.loadSeconds = m_source.lastLoadSeconds();
		const auto t0 = Clock::now();
		e.features = m_sys.extract(e.frame);
		e.extractSeconds = since(t0);
		if (!queue.push(std::move(e))) break;
	}
}

void RecordedFrameLoop::consume(core::BoundedQueue<Extracted>& queue, const std::function<void(const sfm::TrackedFrame&)>& onFrame)
{
	for (;;)
	{
		const auto tWait = Clock::now();
		auto e = queue.pop();
		if (!e) break;
		m_sys.timings().add("input_wait", since(tWait));
		m_sys.timings().add("load", e->loadSeconds);
		m_sys.timings().add("extract", e->extractSeconds);
		const auto t0 = Clock::now();
		onFrame(m_sys.processExtracted(e->frame, std::move(e->features)));
		m_sys.timings().add("track_and_map", since(t0));
		if (e->released) m_sys.timings().add("frame_latency", since(*e->released));
	}
}

}  // namespace keygrid::slam
