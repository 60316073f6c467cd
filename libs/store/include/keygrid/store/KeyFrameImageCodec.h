#pragma once
/** \file KeyFrameImageCodec.h
 * Compresses a keyframe's colour and depth images for the session store and back. Encoding is
 * the costly part of storing a keyframe, so it is separate from SessionStore::write(): run it on
 * another thread (SessionWriter does) and hand the EncodedImages over.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>
#include <keygrid/store/SessionRecords.h>

#include <string>

namespace keygrid::store
{
struct ImageCodecOptions : public core::FieldTableOptions<ImageCodecOptions>
{
	/** Colour image format: "png" (lossless) or "jpg" (lossy, much smaller) (Default: png) */
	std::string colourFormat{"png"};
	/** zlib level of the PNGs, 0 (none) .. 9 (smallest, slowest); the depth PNG always uses it
	 * too (Default: 1, the fastest level that compresses) */
	int pngCompression{1};
	/** JPEG quality 1 .. 100 when colourFormat = jpg (Default: 95) */
	int jpegQuality{95};

	/** Its keys (in [store]). */
	core::OptionFields fields();
	/** Throws std::invalid_argument naming section, key, value and rule of an invalid option. */
	void validate(const std::string& section = "store") const;
};

class KeyFrameImageCodec
{
   public:
	/** Throws std::invalid_argument naming the invalid option. */
	explicit KeyFrameImageCodec(const ImageCodecOptions& opts = {});

	/** colour: CV_8UC3 (BGR) or CV_8UC1, may be empty; depthRaw: CV_16UC1 in the camera's depth
	 * units, may be empty. Throws std::invalid_argument on other image types. */
	EncodedImages encode(const cv::Mat& colour, const cv::Mat& depthRaw) const;
	/** Decodes what encode() produced (exactly, for PNG). Throws std::runtime_error when a
	 * stored image does not decode. */
	static KeyFrameImages decode(const EncodedImages& enc);

	/** Depth [m] (CV_32FC1) to raw units: round(d / depthUnits), 0 where d is not finite or <= 0;
	 * exact for depths that came from raw units. Throws std::invalid_argument naming the depth
	 * when one does not fit 16 bits (> 65535 * depthUnits). */
	static cv::Mat depthToRaw(const cv::Mat& depthMetres, float depthUnits);
	/** Raw units to depth [m] (CV_32FC1): raw * depthUnits, 0 stays 0. */
	static cv::Mat rawToDepth(const cv::Mat& depthRaw, float depthUnits);

	const ImageCodecOptions& options() const { return m_opts; }

   private:
	ImageCodecOptions m_opts;
};

}  // namespace keygrid::store
