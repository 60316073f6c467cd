#pragma once
/** \file TumFrameSource.h
 * Frames from a TUM RGB-D folder (colour PNG + 16-bit depth PNG per pair), or with depth
 * ignored (monocular input) image-only frames from its colour PNGs.
 */
#include <keygrid/core/FrameSource.h>
#include <keygrid/core/TumSequence.h>

namespace keygrid::core
{
class TumFrameSource : public FrameSource
{
   public:
	/** Indexes the folder (see TumSequence; opts.depth = DepthUse::Ignore: its colour images
	 * alone, a folder without depth.txt or depth/ is fine); the camera comes from opts.camera
	 * or is guessed. */
	explicit TumFrameSource(const std::string& dir, const FrameSourceOptions& opts = {});

	bool next(Frame& out) override;
	std::optional<std::size_t> sizeHint() const override { return m_seq.pairs().size(); }
	std::string describe() const override;

	const TumSequence& sequence() const { return m_seq; }
	const RgbdCamera& camera() const { return m_camera; }

	/** Loads pair i: colour (CV_8UC3) and raw depth (CV_16UC1) exactly as stored; with depth
	 * ignored the colour image alone (depthRaw released, no depth file read).
	 * Throws std::runtime_error naming the file when unreadable, of the wrong type, or when
	 * the two images (or the camera) disagree in size. */
	void loadPair(std::size_t i, cv::Mat& colour, cv::Mat& depthRaw) const;

	/** Builds the Frame of pair i (the timestamp is the colour image's; no depth when the
	 * sequence was indexed with depth ignored). */
	void loadFrame(std::size_t i, Frame& out) const;

   private:
	/** Throws naming `path` when the image's size is not the camera's. */
	void checkImageSize(const std::string& path, const cv::Mat& colour) const;

	TumSequence m_seq;
	RgbdCamera m_camera;
	std::size_t m_next{0};
};

}  // namespace keygrid::core
