/** \file CHOCPointsMap_keyframes.cpp
 * CHOCPointsMap in a SLAM run (maps::KeyFrameMap): the frontend's landmarks, outputs and
 * summary.
 */
#include <keygrid/core/AtomicOutput.h>
#include <keygrid/maps/CHOCPointsMap.h>

namespace keygrid
{
void CHOCPointsMap::syncLandmarks(const maps::LandmarkSource& landmarks)
{
	const auto render = renderOptions;
	const auto insertion = insertionOptions;
	const auto likelihood = likelihoodOptions;
	*this = landmarks();
	renderOptions = render;
	insertionOptions = insertion;
	likelihoodOptions = likelihood;
}

void CHOCPointsMap::writeOutputs(maps::MapOutputFolder& out, const std::string& suffix) const
{
	const std::string stem = "hoc_points" + suffix;
	out.write(stem + ".ply", [&](const std::string& p) { saveAsPly(p, out.frame()); });
	out.write(stem + ".bin", [&](const std::string& p) { core::saveGzAtomically(*this, p); });
}

std::string CHOCPointsMap::summaryJsonFields() const { return "\"points\": " + std::to_string(size()); }

}  // namespace keygrid
