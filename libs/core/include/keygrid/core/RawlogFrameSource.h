#pragma once
/** \file RawlogFrameSource.h
 * Streams frames out of an MRPT rawlog (either rawlog format: sensory-frame/action pairs or
 * plain observations), one object at a time: RGB-D frames from CObservation3DRangeScan, or,
 * with depth ignored (monocular input), image-only frames from CObservation3DRangeScan and
 * CObservationImage.
 */
#include <keygrid/core/FrameSource.h>

#include <memory>
#include <string>

namespace mrpt::obs
{
class CObservation;
}

namespace keygrid::core
{
class RawlogFrameSource : public FrameSource
{
   public:
	/** Opens the file; lazy-loaded external images are resolved against the rawlog's
	 * images directory (CRawlog::detectImagesDirectory). Throws if it cannot be opened.
	 * opts.depth = DepthUse::Use: frames from CObservation3DRangeScan; any other observation
	 * (CObservationImage too) is skipped and counted.
	 * opts.depth = DepthUse::Ignore: image-only frames from CObservation3DRangeScan (its
	 * intensity image alone is loaded) and CObservationImage; a CObservationImage without
	 * calibration (rawlog-grabber's USB camera) takes opts.camera. */
	explicit RawlogFrameSource(const std::string& rawlogPath, const FrameSourceOptions& opts = {});
	~RawlogFrameSource() override;

	bool next(Frame& out) override;
	std::optional<std::size_t> sizeHint() const override { return std::nullopt; }
	std::string describe() const override;

	/** Bytes consumed so far and file size, for progress reporting. */
	std::size_t bytesRead() const;
	std::size_t fileSize() const { return m_fileSize; }

   private:
	/** Loads the observation's images (not its depth when depth is ignored) and converts it;
	 * false with the reason, naming the entry, when it cannot be a frame. */
	bool loadAndConvert(const mrpt::obs::CObservation& obs, Frame& out, std::string& why) const;

	struct Impl;
	std::unique_ptr<Impl> m_impl;
	std::string m_path;
	DepthUse m_depth{DepthUse::Use};
	std::optional<RgbdCamera> m_camera;  //!< for image observations without calibration
	std::size_t m_fileSize{0};
	bool m_compressed{false};  //!< gzip file (positions are then in uncompressed bytes)
	std::size_t m_nextIndex{0};
};

}  // namespace keygrid::core
