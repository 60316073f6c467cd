#pragma once
/** \file RawlogFrameSource.h
 * Streams CObservation3DRangeScan frames out of an MRPT rawlog (either rawlog format:
 * sensory-frame/action pairs or plain observations), one object at a time.
 */
#include <keygrid/core/FrameSource.h>

#include <memory>
#include <string>

namespace keygrid::core
{
class RawlogFrameSource : public FrameSource
{
   public:
	/** Opens the file; lazy-loaded external images are resolved against the rawlog's
	 * images directory (CRawlog::detectImagesDirectory). Throws if it cannot be opened. */
	explicit RawlogFrameSource(const std::string& rawlogPath);
	~RawlogFrameSource() override;

	bool next(Frame& out) override;
	std::optional<std::size_t> sizeHint() const override { return std::nullopt; }
	std::string describe() const override;

	/** Bytes consumed so far and file size, for progress reporting. */
	std::size_t bytesRead() const;
	std::size_t fileSize() const { return m_fileSize; }

   private:
	struct Impl;
	std::unique_ptr<Impl> m_impl;
	std::string m_path;
	std::size_t m_fileSize{0};
	bool m_compressed{false};  //!< gzip file (positions are then in uncompressed bytes)
	std::size_t m_nextIndex{0};
};

}  // namespace keygrid::core
