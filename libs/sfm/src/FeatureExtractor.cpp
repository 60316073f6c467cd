#include <keygrid/core/ConfigReading.h>
#include <keygrid/sfm/FeatureExtractor.h>
#include <mrpt/config/CConfigFileBase.h>
#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace keygrid::sfm
{
core::OptionFields FeatureOptions::fields()
{
	using R = core::OptionRule;
	// Integer ranges also bound memory (keypoints, pyramid images, grid cells per frame).
	core::OptionFields f;
	f.add("type", type, "keypoints and descriptors: orb | sift", R::oneOf({"orb", "sift"}));
	f.add("num_features", numFeatures, "keypoints kept per frame", R::inRange(10, kMaxFeatures));
	f.add("scale_factor", scaleFactor, "scale step between pyramid levels", R::between(1, 2));
	f.add("num_levels", numLevels, "pyramid levels", R::inRange(1, 16));
	f.add("fast_threshold", fastThreshold, "ORB FAST corner threshold [grey levels]", R::inRange(1, 255));
	f.add("oversampling", oversampling, "candidates per kept keypoint before bucketing", R::inRange(1, 10));
	f.add("grid_cols", gridCols, "bucketing grid columns", R::inRange(1, 1000));
	f.add("grid_rows", gridRows, "bucketing grid rows", R::inRange(1, 1000));
	f.add("min_depth", minDepth, "valid depth range, lower end [m]", R::atLeast(0));
	f.add("max_depth", maxDepth, "valid depth range, upper end [m] (above min_depth)");
	f.add("max_depth_discontinuity", maxDepthDiscontinuity, "3x3 depth span / depth above which depth is rejected", R::positive());
	f.add("pyramid_pixel_centres", pyramidPixelCentres, "ORB: map pyramid keypoints to level 0 through pixel centres");
	return f;
}

void FeatureOptions::validate(const std::string& s) const
{
	core::validateFields(*this, s);
	if (!(maxDepth > minDepth))
		throw std::invalid_argument("[" + s + "] max_depth = " + std::to_string(maxDepth) + " (must be > min_depth = " + std::to_string(minDepth) + ")");
}

std::vector<cv::KeyPoint> bucketKeypoints(
	const std::vector<cv::KeyPoint>& kps, cv::Size size, int cols, int rows, int budget)
{
	if (static_cast<int>(kps.size()) <= budget) return kps;
	const int cells = cols * rows;
	std::vector<std::vector<int>> byCell(static_cast<std::size_t>(cells));
	for (std::size_t i = 0; i < kps.size(); i++)
	{
		const int cx = std::clamp(static_cast<int>(kps[i].pt.x * cols / size.width), 0, cols - 1);
		const int cy = std::clamp(static_cast<int>(kps[i].pt.y * rows / size.height), 0, rows - 1);
		byCell[static_cast<std::size_t>(cy) * cols + cx].push_back(static_cast<int>(i));
	}
	auto stronger = [&](int a, int b) {
		// Ties broken by position so the result never depends on input order.
		if (kps[a].response != kps[b].response) return kps[a].response > kps[b].response;
		if (kps[a].pt.y != kps[b].pt.y) return kps[a].pt.y < kps[b].pt.y;
		return kps[a].pt.x < kps[b].pt.x;
	};
	const int perCell = std::max(1, budget / cells);
	std::vector<int> kept, rest;
	for (auto& cell : byCell)
	{
		std::sort(cell.begin(), cell.end(), stronger);
		for (std::size_t k = 0; k < cell.size(); k++) (static_cast<int>(k) < perCell ? kept : rest).push_back(cell[k]);
	}
	if (static_cast<int>(kept.size()) > budget)
	{
		std::sort(kept.begin(), kept.end(), stronger);
		kept.resize(static_cast<std::size_t>(budget));
	}
	else
	{
		std::sort(rest.begin(), rest.end(), stronger);
		for (std::size_t k = 0; k < rest.size() && static_cast<int>(kept.size()) < budget; k++) kept.push_back(rest[k]);
	}
	std::sort(kept.begin(), kept.end());
	std::vector<cv::KeyPoint> out;
	out.reserve(kept.size());
	for (int i : kept) out.push_back(kps[i]);
	return out;
}

FeatureExtractor::FeatureExtractor(const FeatureOptions& o) : m_opts(o)
{
	o.validate("features");
	const int n = static_cast<int>(std::ceil(o.numFeatures * o.oversampling));
	if (o.type == "orb")
		m_detector = cv::ORB::create(
			n, static_cast<float>(o.scaleFactor), o.numLevels, 19, 0, 2, cv::ORB::HARRIS_SCORE, 31,
			o.fastThreshold);
	else
		m_detector = cv::SIFT::create(n);
	for (int l = 0; l < std::max(o.numLevels, 16); l++) m_levelScale.push_back(std::pow(o.scaleFactor, l));
}

double FeatureExtractor::levelScale(int level) const
{
	return m_levelScale.at(static_cast<std::size_t>(std::clamp(level, 0, static_cast<int>(m_levelScale.size()) - 1)));
}

float FeatureExtractor::depthAt(const cv::Mat& depth, float u, float v) const
{
	const int c = static_cast<int>(std::lround(u)), r = static_cast<int>(std::lround(v));
	if (c < 1 || r < 1 || c >= depth.cols - 1 || r >= depth.rows - 1) return 0.f;
	const float d = depth.at<float>(r, c);
	if (!(d >= m_opts.minDepth && d <= m_opts.maxDepth)) return 0.f;
	float lo = d, hi = d;
	for (int dr = -1; dr <= 1; dr++)
		for (int dc = -1; dc <= 1; dc++)
		{
			const float x = depth.at<float>(r + dr, c + dc);
			if (x <= 0) continue;  // holes next to a valid pixel are common; not an edge by themselves
			lo = std::min(lo, x);
			hi = std::max(hi, x);
		}
	return (hi - lo) > m_opts.maxDepthDiscontinuity * d ? 0.f : d;
}

// OpenCV's ORB builds level l from level l-1 with cv::resize to cvRound(W / s^l) x cvRound(H / s^l)
// pixels. resize maps a destination pixel centre x to the source position (x + 0.5) * ratio - 0.5;
// chaining the levels telescopes to u0 = (u_l + 0.5) * W / W_l - 0.5, whereas ORB reports
// u_l * s^l: a shift of 0.5 (s^l - 1) px (1.3 px at level 7 with s = 1.2) plus the size rounding.
cv::Point2f FeatureExtractor::levelZeroPosition(const cv::KeyPoint& kp, cv::Size size) const
{
	if (m_opts.type != "orb" || !m_opts.pyramidPixelCentres || kp.octave <= 0) return kp.pt;
	// ORB's own float scale, so that pt / scale gives back the level's integer pixel exactly
	const float s = static_cast<float>(std::pow(m_opts.scaleFactor, static_cast<double>(kp.octave)));
	const double wl = cvRound(size.width / s), hl = cvRound(size.height / s);
	const double ul = kp.pt.x / s, vl = kp.pt.y / s;
	return {static_cast<float>((ul + 0.5) * size.width / wl - 0.5), static_cast<float>((vl + 0.5) * size.height / hl - 0.5)};
}

FrameFeatures FeatureExtractor::extract(const core::Frame& frame) const
{
	if (frame.grey.empty()) throw std::invalid_argument("FeatureExtractor: frame has no image");
	FrameFeatures f;
	f.camera = frame.camera;
	f.levelScale = m_levelScale;
	f.numLevels = m_opts.numLevels;
	std::vector<cv::KeyPoint> all;
	m_detector->detect(frame.grey, all);
	f.keypoints = bucketKeypoints(all, frame.grey.size(), m_opts.gridCols, m_opts.gridRows, m_opts.numFeatures);
	m_detector->compute(frame.grey, f.keypoints, f.descriptors);
	// After compute(): the descriptors were taken at OpenCV's own level position
	for (auto& kp : f.keypoints) kp.pt = levelZeroPosition(kp, frame.grey.size());
	if (m_opts.type == "sift")
	{
		// Pyramid level from the keypoint scale, so matching windows work as for ORB.
		const double base = 3.2, ls = std::log(m_opts.scaleFactor);
		for (auto& kp : f.keypoints)
			kp.octave = std::clamp(static_cast<int>(std::lround(std::log(std::max(kp.size, 1.f) / base) / ls)), 0, m_opts.numLevels - 1);
	}
	const std::size_t n = f.keypoints.size();
	std::vector<cv::Point2f> raw(n);
	for (std::size_t i = 0; i < n; i++) raw[i] = f.keypoints[i].pt;
	if (frame.camera.hasDistortion() && n > 0)
	{
		const cv::Matx33d K(frame.camera.fx, 0, frame.camera.cx, 0, frame.camera.fy, frame.camera.cy, 0, 0, 1);
		const std::vector<double> D(frame.camera.dist.begin(), frame.camera.dist.end());
		cv::undistortPoints(raw, f.undistorted, K, D, cv::noArray(), K);
	}
	else
		f.undistorted = raw;
	f.depth.assign(n, 0.f);
	if (!frame.depth.empty())
		for (std::size_t i = 0; i < n; i++) f.depth[i] = depthAt(frame.depth, raw[i].x, raw[i].y);
	f.buildGrid();
	return f;
}

}  // namespace keygrid::sfm
