#include <keygrid/core/ConfigReading.h>
#include <keygrid/core/Frame.h>
#include <keygrid/store/KeyFrameImageCodec.h>
#include <mrpt/config/CConfigFileBase.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <stdexcept>

namespace keygrid::store
{
core::OptionFields ImageCodecOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("colour_format", colourFormat, "png (lossless) | jpg", R::oneOf({"png", "jpg"}));
	f.add("png_compression", pngCompression, "zlib level of the PNGs", R::inRange(0, 9));
	f.add("jpeg_quality", jpegQuality, "JPEG quality of the colour images when colour_format = jpg", R::inRange(1, 100));
	return f;
}

void ImageCodecOptions::validate(const std::string& section) const { core::validateFields(*this, section); }

KeyFrameImageCodec::KeyFrameImageCodec(const ImageCodecOptions& opts) : m_opts(opts)
{
	m_opts.validate();
}

EncodedImages KeyFrameImageCodec::encode(const cv::Mat& colour, const cv::Mat& depthRaw) const
{
	if (!colour.empty() && colour.type() != CV_8UC3 && colour.type() != CV_8UC1)
		throw std::invalid_argument("KeyFrameImageCodec::encode: colour image must be CV_8UC3 or CV_8UC1, got type " +
									std::to_string(colour.type()));
	if (!depthRaw.empty() && depthRaw.type() != CV_16UC1)
		throw std::invalid_argument("KeyFrameImageCodec::encode: depth image must be CV_16UC1 (raw units), got type " +
									std::to_string(depthRaw.type()));
	EncodedImages out;
	out.colourFormat = m_opts.colourFormat;
	const std::vector<int> png = {cv::IMWRITE_PNG_COMPRESSION, m_opts.pngCompression};
	if (!colour.empty())
	{
		const std::vector<int> jpg = {cv::IMWRITE_JPEG_QUALITY, m_opts.jpegQuality};
		const bool isPng = m_opts.colourFormat == "png";
		if (!cv::imencode(isPng ? ".png" : ".jpg", colour, out.colour, isPng ? png : jpg))
			throw std::runtime_error("KeyFrameImageCodec::encode: OpenCV could not encode the colour image");
	}
	if (!depthRaw.empty() && !cv::imencode(".png", depthRaw, out.depth, png))
		throw std::runtime_error("KeyFrameImageCodec::encode: OpenCV could not encode the depth image");
	return out;
}

KeyFrameImages KeyFrameImageCodec::decode(const EncodedImages& enc)
{
	KeyFrameImages out;
	if (!enc.colour.empty())
	{
		out.colour = cv::imdecode(enc.colour, cv::IMREAD_UNCHANGED);
		if (out.colour.empty()) throw std::runtime_error("the " + enc.colourFormat + " colour image does not decode");
	}
	if (!enc.depth.empty())
	{
		out.depthRaw = cv::imdecode(enc.depth, cv::IMREAD_UNCHANGED);
		if (out.depthRaw.type() != CV_16UC1) throw std::runtime_error("the depth image does not decode to a 16-bit image");
	}
	return out;
}

cv::Mat KeyFrameImageCodec::depthToRaw(const cv::Mat& depthMetres, float depthUnits)
{
	if (depthMetres.empty()) return {};
	if (depthMetres.type() != CV_32FC1)
		throw std::invalid_argument("KeyFrameImageCodec::depthToRaw: depth must be CV_32FC1 [m], got type " +
									std::to_string(depthMetres.type()));
	if (!(depthUnits > 0))
		throw std::invalid_argument("KeyFrameImageCodec::depthToRaw: depthUnits must be > 0, got " + std::to_string(depthUnits));
	cv::Mat raw(depthMetres.size(), CV_16UC1);
	for (int r = 0; r < depthMetres.rows; r++)
	{
		const float* d = depthMetres.ptr<float>(r);
		auto* o = raw.ptr<std::uint16_t>(r);
		for (int c = 0; c < depthMetres.cols; c++)
		{
			if (!(d[c] > 0) || !std::isfinite(d[c]))
			{
				o[c] = 0;
				continue;
			}
			const double q = std::round(static_cast<double>(d[c]) / depthUnits);
			if (q > 65535.0)
				throw std::invalid_argument("KeyFrameImageCodec::depthToRaw: depth " + std::to_string(d[c]) +
											" m does not fit 16 bits at depth units " + std::to_string(depthUnits) + " m");
			o[c] = static_cast<std::uint16_t>(q);
		}
	}
	return raw;
}

cv::Mat KeyFrameImageCodec::rawToDepth(const cv::Mat& depthRaw, float depthUnits)
{
	if (depthRaw.empty()) return {};
	if (depthRaw.type() != CV_16UC1)
		throw std::invalid_argument("KeyFrameImageCodec::rawToDepth: depth must be CV_16UC1, got type " + std::to_string(depthRaw.type()));
	return core::depthRawToMetres(depthRaw, depthUnits);
}

}  // namespace keygrid::store
