/** The navigation-safety metrics, cell verdicts, overlay image and visibility mask of
 * OccupancyGridMetrics.h on hand-made grids whose answers are counted by hand in the comments. */
#include <keygrid/maps/OccupancyGridMetrics.h>
#include <mrpt/img/CImage.h>
#include <mrpt/math/CMatrixFixed.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "TestData.h"

using namespace keygrid::maps;
using keygrid::CellState;

namespace
{
/** A grid drawn as rows of characters, the first string is cy = 0 (lowest y), 1 m cells from
 * (0, 0); `cellOf` turns a character into the grid's cell value. */
template <class Grid, class CellOf>
Grid gridFromRows(const std::vector<std::string>& rows, CellOf cellOf)
{
	Grid g;
	g.resolution = 1.0;
	g.sizeX = static_cast<int>(rows[0].size());
	g.sizeY = static_cast<int>(rows.size());
	for (const auto& r : rows)
		for (const char c : r) g.cells.push_back(cellOf(c));
	return g;
}

/** Plan: 'O' occupied, '.' free. */
FloorPlanGrid plan(const std::vector<std::string>& rows)
{
	return gridFromRows<FloorPlanGrid>(rows, [](char c) { return c == 'O' ? FloorPlanGrid::Occupied : FloorPlanGrid::Free; });
}

/** Estimate: 'O' occupied, 'F' free, '?' unknown. */
TriStateGrid estimate(const std::vector<std::string>& rows)
{
	return gridFromRows<TriStateGrid>(
		rows, [](char c) { return c == 'O' ? CellState::Occupied : c == 'F' ? CellState::Free : CellState::Unknown; });
}

// A 4 x 3 obstacle (x 2..5, y 1..3): 12 cells, 2 interior ((3,2), (4,2): no free cell among
// their 8 neighbours), 10 on the boundary; 36 free cells.
const std::vector<std::string> kPlan = {
	"........",  // cy 0
	"..OOOO..",  // cy 1
	"..OOOO..",  // cy 2
	"..OOOO..",  // cy 3
	"........",  // cy 4
	"........",  // cy 5
};
// Estimate: (3,2) interior called free = 1 hazard; (4,1) and (5,3) edges called free; (5,1)
// unknown with no occupied 4-neighbour = the only unmatched obstacle cell; (1,4) a false
// obstacle; column x = 7 and (0,3) unknown.
const std::vector<std::string> kEst = {
	"FFFFFFF?",  // cy 0
	"FFOOF?F?",  // cy 1
	"FFOFO?F?",  // cy 2
	"?F??OFF?",  // cy 3
	"FOFFFFF?",  // cy 4
	"FFFFFFF?",  // cy 5
};

OccupancyMetricsOptions oneCell()
{
	OccupancyMetricsOptions o;
	o.matchTolerance = 1.0;  // one 1 m cell: the 4-neighbourhood
	return o;
}

/** The recalls over what was in view, counted by hand: `boundary` obstacle boundary cells seen,
 * `matched` of them matched; `free` free cells seen, `calledFree` of them called free. */
void expectSeenRecalls(const OccupancyMetrics& m, std::size_t boundary, std::size_t matched, std::size_t free, std::size_t calledFree)
{
	EXPECT_EQ(m.gtBoundarySeen, boundary);
	EXPECT_EQ(m.gtBoundarySeenMatched, matched);
	EXPECT_DOUBLE_EQ(m.boundaryRecall, static_cast<double>(matched) / static_cast<double>(boundary));
	EXPECT_EQ(m.gtFreeSeen, free);
	EXPECT_EQ(m.gtFreeSeenCalledFree, calledFree);
	EXPECT_DOUBLE_EQ(m.freeRecall, static_cast<double>(calledFree) / static_cast<double>(free));
}
}  // namespace

TEST(OccupancyGridMetrics, NavigationSafetyCountedByHand)
{
	const auto m = evaluateOccupancy(estimate(kEst), plan(kPlan), oneCell());
	EXPECT_EQ(m.gtOccupied, 12u);
	EXPECT_EQ(m.gtOccupiedInterior, 2u);
	EXPECT_EQ(m.hazardCells, 1u);           // (3,2)
	EXPECT_EQ(m.gtOccupiedCalledFree, 3u);  // (3,2), (4,1), (5,3)
	// Every obstacle cell but (5,1) has an estimated occupied cell within one cell.
	EXPECT_EQ(m.gtOccupiedMatched, 11u);
	// Boundary = the 10 non-interior cells, all in view without a mask; 9 matched. Without a
	// mask every one of the 36 GT-free cells counts; 28 are called free.
	expectSeenRecalls(m, 10, 9, 36, 28);
	// Estimated occupied: 5 on the obstacle + (1,4).
	EXPECT_EQ(m.estOccupied, 6u);
	EXPECT_EQ(m.estOccupiedMatched, 5u);
	EXPECT_DOUBLE_EQ(m.precision, 5.0 / 6.0);
	// Estimated free: rows 7 + 4 + 4 + 3 + 6 + 7 = 31, of which 3 on the obstacle.
	EXPECT_EQ(m.estFree, 31u);
	EXPECT_EQ(m.estFreeCorrect, 28u);
	EXPECT_DOUBLE_EQ(m.freePrecision, 28.0 / 31.0);
	// Harmonic mean of 28/31 and 28/36 = 2 * 28 / (31 + 36).
	EXPECT_NEAR(m.freeF1, 56.0 / 67.0, 1e-12);
	// The existing free accuracy: 29 GT-free cells observed (36 - 7 unknown), 28 correct.
	EXPECT_EQ(m.gtFreeObserved, 29u);
	EXPECT_EQ(m.gtFreeCorrect, 28u);
}

TEST(OccupancyGridMetrics, HazardMarginWidensOrNarrowsTheInterior)
{
	auto o = oneCell();
	o.hazardMarginCells = 0;  // every obstacle cell is interior: all 3 called free are hazards
	auto m = evaluateOccupancy(estimate(kEst), plan(kPlan), o);
	EXPECT_EQ(m.gtOccupiedInterior, 12u);
	EXPECT_EQ(m.hazardCells, 3u);
	o.hazardMarginCells = 2;  // the obstacle is 3 cells high: no cell is 2 cells from free
	m = evaluateOccupancy(estimate(kEst), plan(kPlan), o);
	EXPECT_EQ(m.gtOccupiedInterior, 0u);
	EXPECT_EQ(m.hazardCells, 0u);
	o.hazardMarginCells = -1;
	EXPECT_THROW(evaluateOccupancy(estimate(kEst), plan(kPlan), o), std::invalid_argument);
}

TEST(OccupancyGridMetrics, VisibilityMaskRestrictsRecallNotPrecision)
{
	FloorPlanGrid gt = plan(kPlan);
	gt.seen.assign(gt.cells.size(), 0);
	auto see = [&](int cx, int cy, uint8_t bit) { gt.seen[cx + cy * gt.sizeX] |= bit; };
	// Surfaces seen: (2,1), (3,1), (5,1), (2,2): 4 boundary cells, 3 matched ((5,1) is not).
	for (const auto& [x, y] : {std::pair{2, 1}, {3, 1}, {5, 1}, {2, 2}}) see(x, y, FloorPlanGrid::SeenSurface);
	// Free space seen: rows cy 0 and 4 (16 cells); called free: 7 + 6 = 13 ((7,0), (7,4)
	// unknown, (1,4) occupied).
	for (int x = 0; x < 8; x++)
	{
		see(x, 0, FloorPlanGrid::SeenFreeSpace);
		see(x, 4, FloorPlanGrid::SeenFreeSpace);
	}
	// A free-space bit on an obstacle cell and a surface bit on a free cell change nothing.
	see(3, 2, FloorPlanGrid::SeenFreeSpace);
	see(0, 5, FloorPlanGrid::SeenSurface);
	const auto m = evaluateOccupancy(estimate(kEst), gt, oneCell());
	expectSeenRecalls(m, 4, 3, 16, 13);
	const double p = 28.0 / 31.0, r = 13.0 / 16.0;
	EXPECT_NEAR(m.freeF1, 2 * p * r / (p + r), 1e-12);
	// Unchanged by the mask: hazards, precision, the all-cells recall.
	EXPECT_EQ(m.hazardCells, 1u);
	EXPECT_DOUBLE_EQ(m.precision, 5.0 / 6.0);
	EXPECT_EQ(m.gtOccupiedMatched, 11u);

	gt.seen.pop_back();
	EXPECT_THROW(evaluateOccupancy(estimate(kEst), gt, oneCell()), std::invalid_argument);
}

TEST(OccupancyGridMetrics, VerdictsAgreeWithTheMetrics)
{
	FloorPlanGrid gt = plan(kPlan);
	const auto v = classifyCells(estimate(kEst), gt, oneCell());
	ASSERT_EQ(v.size(), 48u);
	auto at = [&](int cx, int cy) { return v[cx + cy * 8]; };
	EXPECT_EQ(at(3, 2), CellVerdict::Hazard);
	EXPECT_EQ(at(4, 1), CellVerdict::EdgeCalledFree);
	EXPECT_EQ(at(5, 3), CellVerdict::EdgeCalledFree);
	EXPECT_EQ(at(5, 1), CellVerdict::Missed);
	EXPECT_EQ(at(5, 2), CellVerdict::Occupied);  // unknown itself, (4,2) occupied next to it
	EXPECT_EQ(at(1, 4), CellVerdict::FalseObstacle);
	EXPECT_EQ(at(7, 0), CellVerdict::Unknown);
	EXPECT_EQ(at(0, 0), CellVerdict::Free);
	size_t n[kCellVerdictCount] = {};
	for (const auto c : v) n[static_cast<int>(c)]++;
	// Occupied: (2,1) (3,1) (2,2) (4,2) (4,3) themselves, (5,2) (2,3) (3,3) by a neighbour.
	EXPECT_EQ(n[static_cast<int>(CellVerdict::Occupied)], 8u);
	EXPECT_EQ(n[static_cast<int>(CellVerdict::Hazard)], 1u);
	EXPECT_EQ(n[static_cast<int>(CellVerdict::EdgeCalledFree)], 2u);
	EXPECT_EQ(n[static_cast<int>(CellVerdict::Missed)], 1u);
	EXPECT_EQ(n[static_cast<int>(CellVerdict::MissedUnseen)], 0u);
	EXPECT_EQ(n[static_cast<int>(CellVerdict::FalseObstacle)], 1u);
	EXPECT_EQ(n[static_cast<int>(CellVerdict::Free)], 28u);
	EXPECT_EQ(n[static_cast<int>(CellVerdict::Unknown)], 7u);
	// With a mask that does not show (5,1) its miss is "never in view".
	gt.seen.assign(gt.cells.size(), FloorPlanGrid::SeenSurface | FloorPlanGrid::SeenFreeSpace);
	gt.seen[5 + 1 * 8] = 0;
	EXPECT_EQ(classifyCells(estimate(kEst), gt, oneCell())[5 + 1 * 8], CellVerdict::MissedUnseen);
}

TEST(OccupancyGridMetrics, OverlayImageColoursEveryCellByItsVerdict)
{
	const std::string path = keygrid::test::scratchDir("overlay") + "/overlay.png";
	OverlayImageOptions io;
	io.pixelsPerCell = 3;
	const auto counts = saveOverlayImage(path, estimate(kEst), plan(kPlan), oneCell(), io);
	EXPECT_EQ(counts[static_cast<int>(CellVerdict::Hazard)], 1u);
	EXPECT_EQ(counts[static_cast<int>(CellVerdict::Free)], 28u);
	mrpt::img::CImage img;
	ASSERT_TRUE(img.loadFromFile(path));
	// 8 x 6 cells of 3 px, legend under it at least 330 px wide, 6 + 8 * 16 + 6 px high.
	EXPECT_EQ(img.getWidth(), 330u);
	EXPECT_EQ(img.getHeight(), 6u * 3u + 140u);
	auto colourOfCell = [&](int cx, int cy) {
		const int u = cx * 3 + 1, v = (6 - 1 - cy) * 3 + 1;  // +y up
		const auto* px = img(u, v);  // MRPT keeps loaded colour images as BGR
		return std::array<uint8_t, 3>{px[2], px[1], px[0]};
	};
	EXPECT_EQ(colourOfCell(3, 2), cellVerdictColour(CellVerdict::Hazard));
	EXPECT_EQ(colourOfCell(4, 1), cellVerdictColour(CellVerdict::EdgeCalledFree));
	EXPECT_EQ(colourOfCell(5, 1), cellVerdictColour(CellVerdict::Missed));
	EXPECT_EQ(colourOfCell(1, 4), cellVerdictColour(CellVerdict::FalseObstacle));
	EXPECT_EQ(colourOfCell(2, 1), cellVerdictColour(CellVerdict::Occupied));
	EXPECT_EQ(colourOfCell(7, 0), cellVerdictColour(CellVerdict::Unknown));
	EXPECT_EQ(colourOfCell(0, 5), cellVerdictColour(CellVerdict::Free));
	EXPECT_EQ(cellVerdictColour(CellVerdict::Hazard), (std::array<uint8_t, 3>{255, 0, 0}));

	EXPECT_THROW(saveOverlayImage("/nonexistent-dir/x.png", estimate(kEst), plan(kPlan)), std::runtime_error);
	io.pixelsPerCell = 0;
	EXPECT_THROW(saveOverlayImage(path, estimate(kEst), plan(kPlan), oneCell(), io), std::invalid_argument);
}

namespace
{
/** Camera at (x, y, z) looking along +x (optical z = +x, optical x = -y, optical y = -z). */
mrpt::poses::CPose3D lookingAlongX(double x, double y, double z)
{
	mrpt::math::CMatrixDouble44 H;
	H.setZero();
	H(0, 2) = 1;
	H(1, 0) = -1;
	H(2, 1) = -1;
	H(0, 3) = x;
	H(1, 3) = y;
	H(2, 3) = z;
	H(3, 3) = 1;
	return mrpt::poses::CPose3D(H);
}

/** One pixel column, three rows: v = 0 up 45 deg, v = 1 level, v = 2 down 45 deg. */
keygrid::core::RgbdCamera columnCamera()
{
	keygrid::core::RgbdCamera c;
	c.width = 1;
	c.height = 3;
	c.fx = c.fy = 1;
	c.cx = 0;
	c.cy = 1;
	return c;
}

FloorPlanGrid emptyPlan()
{
	FloorPlanGrid g;  // 0.5 m cells, x 0..5 m, y 0..2 m
	g.resolution = 0.5;
	g.sizeX = 10;
	g.sizeY = 4;
	g.cells.assign(40, FloorPlanGrid::Free);
	return g;
}

std::string seenRow(const FloorPlanGrid& g, int cy)
{
	std::string s;
	for (int cx = 0; cx < g.sizeX; cx++) s += static_cast<char>('0' + g.seen[cx + cy * g.sizeX]);
	return s;
}
}  // namespace

TEST(OccupancyGridMetrics, SeenCellsOfAHandMadeDepthColumn)
{
	// Camera 1 m high in cell (0, 0), centre (0.25, 0.25). Depths: v = 0 the ceiling 1.6 m up
	// the 45-degree ray at (1.85, 0.25, 2.6): above the band, its band part reaches x = 1.05;
	// v = 1 a wall at x = 3.25 (depth 3): surface cell 6, free cells 0..5 (its own cell 6 not);
	// v = 2 the floor at (1.25, 0.25, 0) (depth 1): band part to x = 1.15, floor cell 2.
	cv::Mat depth(3, 1, CV_32FC1);
	depth.at<float>(0) = 1.6f;
	depth.at<float>(1) = 3.0f;
	depth.at<float>(2) = 1.0f;
	FloorPlanVisibilityOptions o;
	o.freeRayStride = 1;
	FloorPlanGrid g = emptyPlan();
	markSeenCells(g, depth, columnCamera(), lookingAlongX(0.25, 0.25, 1.0), o);
	// 2 = SeenFreeSpace, 1 = SeenSurface, 4 = SeenFloor: the floor ray is below the band
	// (z < 0.1) only over its last 0.1 m, x = 1.15..1.25, all in cell 2.
	EXPECT_EQ(seenRow(g, 0), "2262221000");
	for (int cy = 1; cy < 4; cy++) EXPECT_EQ(seenRow(g, cy), "0000000000") << cy;

	// 2 m range: the wall is out of range, free space ends at x = 0.25 + 2 = 2.25 (cell 4).
	o.maxRange = 2.0;
	g = emptyPlan();
	markSeenCells(g, depth, columnCamera(), lookingAlongX(0.25, 0.25, 1.0), o);
	EXPECT_EQ(seenRow(g, 0), "2262200000");

	// A wall exactly on the boundary x = 3.0 marks both cells' surfaces; free up to cell 5.
	o.maxRange = 4.5;
	depth.at<float>(1) = 2.75f;
	g = emptyPlan();
	markSeenCells(g, depth, columnCamera(), lookingAlongX(0.25, 0.25, 1.0), o);
	EXPECT_EQ(seenRow(g, 0), "2262231000");  // cell 5: both bits

	// A camera above the band sees nothing of it along a level ray.
	cv::Mat level(3, 1, CV_32FC1, cv::Scalar(0.0f));
	level.at<float>(1) = 3.0f;
	g = emptyPlan();
	markSeenCells(g, level, columnCamera(), lookingAlongX(0.25, 0.25, 2.2), o);
	EXPECT_EQ(seenRow(g, 0), "0000000000");

	EXPECT_THROW(markSeenCells(g, cv::Mat(3, 2, CV_32FC1), columnCamera(), lookingAlongX(0, 0, 1), o), std::invalid_argument);
	EXPECT_THROW(markSeenCells(g, cv::Mat(3, 1, CV_16UC1), columnCamera(), lookingAlongX(0, 0, 1), o), std::invalid_argument);
	o.zMin = 2.0;
	o.zMax = 1.0;
	EXPECT_THROW(markSeenCells(g, depth, columnCamera(), lookingAlongX(0, 0, 1), o), std::invalid_argument);
}
