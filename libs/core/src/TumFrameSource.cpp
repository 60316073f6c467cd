#include <keygrid/core/ImageReading.h>
#include <keygrid/core/RawlogFrameSource.h>
#include <keygrid/core/TumFrameSource.h>
#include <mrpt/system/filesystem.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <stdexcept>

namespace keygrid::core
{
TumFrameSource::TumFrameSource(const std::string& dir, const FrameSourceOptions& opts)
	: m_seq(dir, opts.maxAssociationDt, opts.depth),
	  m_camera(opts.camera ? *opts.camera : m_seq.guessCamera())
{
	for (const auto& is : m_seq.issues()) noteSkip(is.str());
}

std::string TumFrameSource::describe() const
{
	return "TUM folder " + m_seq.dir() + " (" + std::to_string(m_seq.pairs().size()) +
		(m_seq.hasDepth() ? " pairs from " : " images from ") + m_seq.indexSource() +
		(m_seq.hasDepth() ? "" : ", depth ignored") + ", camera " + m_camera.name + ")";
}

void TumFrameSource::loadPair(std::size_t i, cv::Mat& colour, cv::Mat& depthRaw) const
{
	const TumPair& p = m_seq.pairs().at(i);
	if (!mrpt::system::fileExists(p.rgbPath)) throw std::runtime_error("missing image '" + p.rgbPath + "'");
	if (m_seq.hasDepth() && !mrpt::system::fileExists(p.depthPath))
		throw std::runtime_error("missing image '" + p.depthPath + "'");
	colour = readImage(p.rgbPath, cv::IMREAD_COLOR);
	if (colour.empty()) throw std::runtime_error("cannot decode image '" + p.rgbPath + "'");
	if (!m_seq.hasDepth())
	{
		depthRaw.release();
		checkImageSize(p.rgbPath, colour);
		return;
	}
	depthRaw = readImage(p.depthPath, cv::IMREAD_ANYDEPTH);
	if (depthRaw.empty()) throw std::runtime_error("cannot decode depth image '" + p.depthPath + "'");
	if (depthRaw.type() != CV_16UC1)
		throw std::runtime_error(
			"depth image '" + p.depthPath + "' is not 16-bit single channel (TUM depth is uint16 PNG)");
	if (colour.size() != depthRaw.size())
		throw std::runtime_error(
			"image sizes differ: '" + p.rgbPath + "' is " + std::to_string(colour.cols) + "x" +
			std::to_string(colour.rows) + ", '" + p.depthPath + "' is " +
			std::to_string(depthRaw.cols) + "x" + std::to_string(depthRaw.rows));
	checkImageSize(p.rgbPath, colour);
}

void TumFrameSource::checkImageSize(const std::string& path, const cv::Mat& colour) const
{
	if (static_cast<unsigned>(colour.cols) != m_camera.width ||
		static_cast<unsigned>(colour.rows) != m_camera.height)
		throw std::runtime_error(
			"image '" + path + "' is " + std::to_string(colour.cols) + "x" +
			std::to_string(colour.rows) + " but camera '" + m_camera.name + "' is " +
			std::to_string(m_camera.width) + "x" + std::to_string(m_camera.height));
}

void TumFrameSource::loadFrame(std::size_t i, Frame& out) const
{
	loadPair(i, out.colour, out.depthRaw);
	cv::cvtColor(out.colour, out.grey, cv::COLOR_BGR2GRAY);
	if (m_seq.hasDepth())
		out.depth = depthRawToMetres(out.depthRaw, m_camera.depthUnits);
	else
		out.depth.release();
	out.camera = m_camera;
	out.timestamp = m_seq.pairs()[i].tRgb;
	out.index = i;
}

bool TumFrameSource::next(Frame& out)
{
	if (m_next >= m_seq.pairs().size()) return false;
	loadFrame(m_next, out);
	++m_next;
	return true;
}

std::unique_ptr<FrameSource> openFrameSource(const std::string& path, const FrameSourceOptions& opts)
{
	if (mrpt::system::directoryExists(path)) return std::make_unique<TumFrameSource>(path, opts);
	std::error_code ec;
	if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec))
		throw std::runtime_error("input '" + path + "' is neither a rawlog file nor a TUM folder (a device or a pipe?)");
	if (mrpt::system::fileExists(path)) return std::make_unique<RawlogFrameSource>(path, opts);
	throw std::runtime_error("input '" + path + "' does not exist");
}

}  // namespace keygrid::core
