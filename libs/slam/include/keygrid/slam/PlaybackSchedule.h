#pragma once
/** \file PlaybackSchedule.h
 * When a recorded frame is released to the pipeline with `[slam] playback_rate` > 0: at the
 * pace of its timestamps, as a camera delivers its frames, so that a threaded run of a
 * recording meets the time budget a live camera gives (tracking and local mapping share the
 * cores as they would live). A frame the pipeline is not ready for waits in the queues; none is
 * dropped (keygrid-slam --live drops them, RecordedFrameLoop keeps every frame of the file).
 */
#include <optional>

namespace keygrid::slam
{
class PlaybackSchedule
{
   public:
	/** A gap between two timestamps counts for at most this long [s]: a recording paused or
	 * with a damaged stamp does not stall the run. */
	static constexpr double kMaxGap = 1.0;

	/** `rate` > 0: the recording's pace times rate (1: as recorded, 2: twice as fast).
	 * Throws std::invalid_argument for a rate that is not positive and finite. */
	explicit PlaybackSchedule(double rate);

	/** When the frame stamped `timestamp` [s] is due, in seconds after the first frame's
	 * release: the sum of the gaps to each earlier frame, each divided by the rate and at most
	 * kMaxGap. Call once per frame in input order; a stamp not after the previous one
	 * (the frame loop drops those) adds no time. */
	double release(double timestamp);

   private:
	double m_rate;
	std::optional<double> m_lastStamp;
	double m_due{0.0};
};

}  // namespace keygrid::slam
