#pragma once
/** \file SyntheticTum.h
 * Writes small TUM RGB-D folders with known content for tests (random colour, random full-range
 * uint16 depth, lists with comments), so conversion tests run without ../shared/data.
 */
#include <opencv2/core/mat.hpp>

#include <string>
#include <vector>

namespace keygrid::test
{
struct SyntheticTum
{
	std::string dir;
	std::vector<double> tRgb, tDepth;
	std::vector<cv::Mat> colour, depthRaw;  //!< exactly what was written
};

/** Writes `n` pairs of w x h images into dir (rgb/, depth/, rgb.txt, depth.txt; associations.txt
 * when withAssociations). Depth timestamps lag colour by depthLag seconds. */
SyntheticTum writeSyntheticTum(
	const std::string& dir, int n, int w = 64, int h = 48, bool withAssociations = true,
	double depthLag = 0.004, unsigned seed = 1);

}  // namespace keygrid::test
