#pragma once
/** \file RecordedRun.h
 * keygrid-slam on a recorded input (rawlog or TUM folder): the frame loop. Decoding runs ahead
 * on the PrefetchingFrameSource's thread, feature extraction on a producer thread, and the
 * calling thread tracks (in sequential mode also maps and closes loops) in input order; the
 * stages are joined by typed bounded queues. Decoding and extraction are functions of the frame
 * alone, so running them ahead keeps sequential mode deterministic.
 */
#include <keygrid/core/BoundedQueue.h>
#include <keygrid/core/PrefetchingFrameSource.h>
#include <keygrid/sfm/Tracker.h>

#include <functional>
#include <string>

namespace keygrid::slam
{
class System;

struct RecordedLoopOptions
{
	/** Input frames skipped before the first processed one (Default: 0) */
	std::size_t firstFrame{0};
	/** Stop after this many processed frames (Default: 0 = all) */
	std::size_t maxFrames{0};
	/** > 0: frames are released at their timestamps' pace times this factor, as a camera
	 * delivers them (PlaybackSchedule); 0: as fast as the pipeline takes them ([slam]
	 * playback_rate) (Default: 0) */
	double playbackRate{0.0};
};

/** Frames dropped for their timestamps: a frame without one, or not after the previous
 * frame's, would give the trajectory a repeated or backward stamp. */
struct TimestampSkips
{
	std::size_t count{0};
	std::string last;  //!< why the latest one was dropped ("" if none)
};

class RecordedFrameLoop
{
   public:
	/** `sys` and `source` must outlive the loop. */
	RecordedFrameLoop(System& sys, core::PrefetchingFrameSource& source, const RecordedLoopOptions& opts);

	/** Runs the frames of the source through the System until the source ends, maxFrames or
	 * interruptRequested(); calls onFrame after each processed frame. Adds the "input_wait",
	 * "load", "extract" and "track_and_map" stage timings, and with a playback rate
	 * "frame_latency" (from the time a frame is due to its tracked pose). Rethrows an error of the source, of
	 * feature extraction or of the processing after the frames before it were processed. */
	void run(const std::function<void(const sfm::TrackedFrame&)>& onFrame);

	/** The frames the producer dropped for their timestamps (complete once run() returned or
	 * threw). */
	const TimestampSkips& timestampSkips() const { return m_timestampSkips; }

   private:
	struct Extracted;

	/** The producer thread's work: skips the first frames, drops frames whose time does not go
	 * forward, waits for each frame's release (playbackRate), extracts features and pushes the
	 * frames until the end, the frame limit, an interruption or a closed queue. */
	void produce(core::BoundedQueue<Extracted>& queue);
	/** The calling thread's work: tracks and maps each extracted frame in order. */
	void consume(core::BoundedQueue<Extracted>& queue, const std::function<void(const sfm::TrackedFrame&)>& onFrame);

	System& m_sys;
	core::PrefetchingFrameSource& m_source;
	RecordedLoopOptions m_opts;
	TimestampSkips m_timestampSkips;  //!< written by the producer thread, read after it joined
};

}  // namespace keygrid::slam
