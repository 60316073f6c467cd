#include <keygrid/core/AtomicOutput.h>
/** \file OccupancyGridMetrics_overlay.cpp
 * The overlay image of an estimated grid on a ground-truth floor plan (saveOverlayImage). */
#include <keygrid/maps/OccupancyGridMetrics.h>
#include <mrpt/img/CImage.h>
#include <mrpt/img/TColor.h>

#include <algorithm>
#include <stdexcept>

namespace keygrid::maps
{
bool OverlayImageOptions::isValid(std::string* error) const
{
	std::string why;
	if (pixelsPerCell < 1 || pixelsPerCell > 64)
		why = "pixelsPerCell must be in [1, 64] (got " + std::to_string(pixelsPerCell) + ")";
	if (error) *error = why;
	return why.empty();
}

std::array<uint8_t, 3> cellVerdictColour(CellVerdict v)
{
	switch (v)
	{
		case CellVerdict::Unknown: return {190, 190, 190};
		case CellVerdict::Free: return {255, 255, 255};
		case CellVerdict::Occupied: return {20, 20, 20};
		case CellVerdict::Missed: return {255, 150, 0};
		case CellVerdict::MissedUnseen: return {225, 205, 150};
		case CellVerdict::EdgeCalledFree: return {255, 150, 190};
		case CellVerdict::Hazard: return {255, 0, 0};
		case CellVerdict::FalseObstacle: return {30, 90, 255};
	}
	return {0, 0, 0};
}

std::array<size_t, kCellVerdictCount> saveOverlayImage(
	const std::string& path, const TriStateGrid& est, const FloorPlanGrid& gt,
	const OccupancyMetricsOptions& metricOpts, const OverlayImageOptions& imageOpts)
{
	std::string why;
	if (!imageOpts.isValid(&why)) throw std::invalid_argument("OverlayImageOptions: " + why);
	if (gt.sizeX < 1 || gt.sizeY < 1)
		throw std::invalid_argument("saveOverlayImage: empty floor plan (" + std::to_string(gt.sizeX) + " x " +
			std::to_string(gt.sizeY) + " cells)");
	const auto verdicts = classifyCells(est, gt, metricOpts);
	std::array<size_t, kCellVerdictCount> counts{};
	for (const auto v : verdicts) counts[static_cast<size_t>(v)]++;

	const int ppc = imageOpts.pixelsPerCell;
	const int mapW = gt.sizeX * ppc, mapH = gt.sizeY * ppc;
	// Legend: one 16 px line per verdict (9x15 font), swatch + "name  count".
	constexpr int kLine = 16, kMargin = 6, kLegendWidth = 330;
	const int legendH = imageOpts.legend ? kMargin + kLine * kCellVerdictCount + kMargin : 0;
	const int W = imageOpts.legend ? std::max(mapW, kLegendWidth) : mapW;
	mrpt::img::CImage img(W, mapH + legendH, mrpt::img::CH_RGB);
	img.filledRectangle(0, 0, W - 1, mapH + legendH - 1, mrpt::img::TColor(255, 255, 255));
	auto colourOf = [](CellVerdict v) {
		const auto c = cellVerdictColour(v);
		return mrpt::img::TColor(c[0], c[1], c[2]);
	};
	for (int cy = 0; cy < gt.sizeY; cy++)
		for (int cx = 0; cx < gt.sizeX; cx++)
		{
			const int row0 = (gt.sizeY - 1 - cy) * ppc;  // +y up
			img.filledRectangle(cx * ppc, row0, cx * ppc + ppc - 1, row0 + ppc - 1,
				colourOf(verdicts[static_cast<size_t>(cx) + static_cast<size_t>(cy) * gt.sizeX]));
		}
	if (imageOpts.legend)
	{
		img.selectTextFont("9x15");
		for (int i = 0; i < kCellVerdictCount; i++)
		{
			const auto v = static_cast<CellVerdict>(i);
			const int y = mapH + kMargin + i * kLine;
			img.filledRectangle(kMargin, y + 2, kMargin + 11, y + 13, colourOf(v));
			img.rectangle(kMargin, y + 2, kMargin + 11, y + 13, mrpt::img::TColor(0, 0, 0));
			img.textOut(kMargin + 18, y, std::string(cellVerdictName(v)) + "  " + std::to_string(counts[i]),
				mrpt::img::TColor(0, 0, 0));
		}
	}
	core::writeFileThrough(path, [&](const std::string& tmp) { return img.saveToFile(tmp); });
	return counts;
}

}  // namespace keygrid::maps
