#include <keygrid/core/Hamming.h>
#include <keygrid/sfm/FrameFeatures.h>

#include <algorithm>
#include <cmath>

namespace keygrid::sfm
{
void FrameFeatures::buildGrid(int cellSizePx)
{
	m_cell = std::max(4, cellSizePx);
	// Undistorted points can fall slightly outside the raw image: pad by a margin of cells.
	m_cols = static_cast<int>(camera.width) / m_cell + 3;
	m_rows = static_cast<int>(camera.height) / m_cell + 3;
	m_grid.assign(static_cast<std::size_t>(m_cols) * m_rows, {});
	for (std::size_t i = 0; i < undistorted.size(); i++)
	{
		const int cx = std::clamp(static_cast<int>(std::floor(undistorted[i].x / m_cell)) + 1, 0, m_cols - 1);
		const int cy = std::clamp(static_cast<int>(std::floor(undistorted[i].y / m_cell)) + 1, 0, m_rows - 1);
		m_grid[static_cast<std::size_t>(cy) * m_cols + cx].push_back(static_cast<int>(i));
	}
}

template <class Visit>
void FrameFeatures::visitArea(float u, float v, float r, int minLevel, int maxLevel, Visit&& visit) const
{
	if (m_grid.empty()) return;
	const int x0 = std::clamp(static_cast<int>(std::floor((u - r) / m_cell)) + 1, 0, m_cols - 1);
	const int x1 = std::clamp(static_cast<int>(std::floor((u + r) / m_cell)) + 1, 0, m_cols - 1);
	const int y0 = std::clamp(static_cast<int>(std::floor((v - r) / m_cell)) + 1, 0, m_rows - 1);
	const int y1 = std::clamp(static_cast<int>(std::floor((v + r) / m_cell)) + 1, 0, m_rows - 1);
	const float r2 = r * r;
	for (int y = y0; y <= y1; y++)
		for (int x = x0; x <= x1; x++)
			for (int i : m_grid[static_cast<std::size_t>(y) * m_cols + x])
			{
				const int lvl = keypoints[i].octave;
				if (minLevel >= 0 && lvl < minLevel) continue;
				if (maxLevel >= 0 && lvl > maxLevel) continue;
				const float dx = undistorted[i].x - u, dy = undistorted[i].y - v;
				if (dx * dx + dy * dy <= r2 && !visit(i)) return;
			}
}

void FrameFeatures::featuresInArea(float u, float v, float r, int minLevel, int maxLevel, std::vector<int>& out) const
{
	out.clear();
	visitArea(u, v, r, minLevel, maxLevel, [&](int i) {
		out.push_back(i);
		return true;
	});
}

std::vector<int> FrameFeatures::featuresInArea(float u, float v, float r, int minLevel, int maxLevel) const
{
	std::vector<int> out;
	featuresInArea(u, v, r, minLevel, maxLevel, out);
	return out;
}

bool FrameFeatures::anyFeatureInArea(float u, float v, float r, int minLevel, int maxLevel) const
{
	bool found = false;
	visitArea(u, v, r, minLevel, maxLevel, [&](int) {
		found = true;
		return false;
	});
	return found;
}

float descriptorDistance(const cv::Mat& a, const cv::Mat& b) { return descriptorDistance(a, 0, b, 0); }

float descriptorDistance(const cv::Mat& a, int ra, const cv::Mat& b, int rb)
{
	if (a.type() == CV_8U) return static_cast<float>(core::hammingDistance(a.ptr<uint64_t>(ra), b.ptr<uint64_t>(rb), a.cols / 8));
	return static_cast<float>(cv::norm(a.row(ra), b.row(rb), cv::NORM_L2));
}

}  // namespace keygrid::sfm
