#pragma once
/** \file LiveRun.h
 * keygrid-slam --live: the real-time frame loop on a camera. A grab thread keeps only the
 * newest camera frame (LiveFrameSource), a producer thread extracts its features, and the
 * calling thread tracks and maps in order and refreshes the optional preview. Frames that
 * arrive while the pipeline is busy are dropped and counted, never queued without bound.
 */
#include <keygrid/sfm/Tracker.h>
#include <keygrid/slam/LiveFrameSource.h>

#include <mrpt/config/CConfigFileBase.h>

#include <functional>
#include <memory>
#include <string>

namespace keygrid::slam
{
class System;
struct SlamConfig;

struct LiveLoopOptions
{
	/** Show the preview window (Default: false) */
	bool preview{false};
	/** Stop after this many processed frames (Default: 0 = until interrupted) */
	std::size_t maxFrames{0};
};

struct LiveLoopResult
{
	std::size_t grabbed{0};  //!< frames the camera delivered
	std::size_t dropped{0};  //!< of those, frames skipped because the pipeline was busy
	bool previewClosed{false};  //!< the user closed the preview window (ends the run)
};

/** Runs frames of `source` through `sys` until the source ends, maxFrames, interruptRequested()
 * or the preview window is closed; calls onFrame after each processed frame. Rethrows an
 * error of the source or of feature extraction after the frames before it were processed. */
LiveLoopResult runLiveLoop(
	System& sys, LiveFrameSource& source, const LiveLoopOptions& opts,
	const std::function<void(const sfm::TrackedFrame&)>& onFrame);

/** Opens the OpenNI2 camera configured in the [live] section of `ini` (COpenNI2Sensor keys
 * plus OpenNI2SourceOptions; [slam] camera other than auto overrides the intrinsics), wrapped
 * in a LiveFrameSource that stops waiting when interruptRequested(). `origin` (the file) starts
 * error messages. */
std::unique_ptr<LiveFrameSource> openLiveCamera(
	const mrpt::config::CConfigFileBase& ini, const std::string& origin, const SlamConfig& cfg);

}  // namespace keygrid::slam
