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
	const std::size_t cells = static_cast<std::size_t>(m_cols) * m_rows;
	std::vector<int> cellOf(undistorted.size());
	m_cellStart.assign(cells + 1, 0);
	for (std::size_t i = 0; i < undistorted.size(); i++)
	{
		const int cx = std::clamp(static_cast<int>(std::floor(undistorted[i].x / m_cell)) + 1, 0, m_cols - 1);
		const int cy = std::clamp(static_cast<int>(std::floor(undistorted[i].y / m_cell)) + 1, 0, m_rows - 1);
		cellOf[i] = cy * m_cols + cx;
		m_cellStart[static_cast<std::size_t>(cellOf[i]) + 1]++;
	}
	for (std::size_t c = 0; c < cells; c++) m_cellStart[c + 1] += m_cellStart[c];
	// Each cell's keypoints in index order, as they were added.
	m_cellItems.assign(undistorted.size(), 0);
	std::vector<int> fill(m_cellStart.begin(), m_cellStart.end() - 1);
	for (std::size_t i = 0; i < undistorted.size(); i++) m_cellItems[static_cast<std::size_t>(fill[static_cast<std::size_t>(cellOf[i])]++)] = static_cast<int>(i);
}

template <class Visit>
void FrameFeatures::visitArea(float u, float v, float r, int minLevel, int maxLevel, Visit&& visit) const
{
	if (m_cellStart.empty()) return;
	const int x0 = std::clamp(static_cast<int>(std::floor((u - r) / m_cell)) + 1, 0, m_cols - 1);
	const int x1 = std::clamp(static_cast<int>(std::floor((u + r) / m_cell)) + 1, 0, m_cols - 1);
	const int y0 = std::clamp(static_cast<int>(std::floor((v - r) / m_cell)) + 1, 0, m_rows - 1);
	const int y1 = std::clamp(static_cast<int>(std::floor((v + r) / m_cell)) + 1, 0, m_rows - 1);
	const float r2 = r * r;
	for (int y = y0; y <= y1; y++)
		for (int x = x0; x <= x1; x++)
		{
			const std::size_t c = static_cast<std::size_t>(y) * m_cols + x;
			for (int k = m_cellStart[c]; k < m_cellStart[c + 1]; k++)
			{
				const int i = m_cellItems[static_cast<std::size_t>(k)];
				const int lvl = keypoints[i].octave;
				if (minLevel >= 0 && lvl < minLevel) continue;
				if (maxLevel >= 0 && lvl > maxLevel) continue;
				const float dx = undistorted[i].x - u, dy = undistorted[i].y - v;
				if (dx * dx + dy * dy <= r2 && !visit(i)) return;
			}
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
