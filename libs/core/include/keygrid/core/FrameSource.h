#pragma once
/** \file FrameSource.h
 * Streams frames from a recorded sequence, one at a time: RGB-D frames, or image-only frames
 * (FrameSourceOptions::depth = DepthUse::Ignore) for the monocular mode.
 */
#include <keygrid/core/Frame.h>

#include <cstddef>
#include <memory>
#include <optional>
#include <string>

namespace keygrid::core
{
/** Sequential reader of frames. Implementations never hold the whole sequence in memory. */
class FrameSource
{
   public:
	virtual ~FrameSource() = default;

	/** Reads the next usable frame into `out`. Returns false at the end of the sequence.
	 * Entries that cannot be frames are skipped and counted (skippedCount / lastSkipReason);
	 * unreadable input (truncated file, missing image) throws std::runtime_error naming it. */
	virtual bool next(Frame& out) = 0;

	/** Number of frames when known in advance (TUM lists), else nullopt (rawlog streams). */
	virtual std::optional<std::size_t> sizeHint() const = 0;

	/** Human-readable description, e.g. "TUM folder /data/fr1_desk (573 pairs)". */
	virtual std::string describe() const = 0;

	std::size_t skippedCount() const { return m_skipped; }
	const std::string& lastSkipReason() const { return m_lastSkip; }

   protected:
	void noteSkip(const std::string& why)
	{
		++m_skipped;
		m_lastSkip = why;
	}

   private:
	std::size_t m_skipped{0};
	std::string m_lastSkip;
};

/** Options shared by the sources that need them. */
struct FrameSourceOptions
{
	/** Camera used for TUM folders, and for rawlog image observations recorded without a
	 * calibration (Default: TUM: preset guessed from the folder name, else "kinect"; rawlog:
	 * none, such observations are skipped) */
	std::optional<RgbdCamera> camera;
	/** Largest |t_rgb - t_depth| accepted when associating TUM lists [s] (Default: 0.02 s) */
	double maxAssociationDt{0.02};
	/** RGB-D frames, or image-only frames for the monocular mode (Default: Use) */
	DepthUse depth{DepthUse::Use};
};

/** Opens `path`: a directory is read as a TUM folder, a file as an MRPT rawlog.
 * Throws std::runtime_error with the reason when it cannot be opened. */
std::unique_ptr<FrameSource> openFrameSource(
	const std::string& path, const FrameSourceOptions& opts = {});

}  // namespace keygrid::core
