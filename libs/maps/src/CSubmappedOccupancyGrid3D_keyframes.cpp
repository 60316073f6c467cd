/** \file CSubmappedOccupancyGrid3D_keyframes.cpp
 * CSubmappedOccupancyGrid3D in a SLAM run (maps::KeyFrameMap): keyframe depth, corrections,
 * outputs and summary.
 */
#include <keygrid/core/AtomicOutput.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>

#include <sstream>
#include <stdexcept>
#include <string>

namespace keygrid
{
void CSubmappedOccupancyGrid3D::insertKeyFrame(const maps::MapKeyFrame& kf, const maps::KeyFrameFeed&)
{
	if (!kf.depth.empty()) insertDepthFrame(kf.depth, kf.camera, kf.T_world_cam, kf.travelled, kf.id);
}

bool CSubmappedOccupancyGrid3D::applyCorrection(const maps::MapCorrection& correction)
{
	// Submaps are morphed rigidly; a rescaled world (monocular map given metric scale) would
	// need its voxels resampled, which the grid does not do. Monocular keyframes carry no
	// depth, so a monocular run leaves this grid empty and never gets here with keyframes.
	if (correction.scale != 1.0 && !keyframes().empty())
		throw std::invalid_argument(
			"CSubmappedOccupancyGrid3D::applyCorrection: cannot rescale a grid built from depth (scale " +
			std::to_string(correction.scale) + ", " + std::to_string(keyframes().size()) + " keyframes)");
	if (correction.scale != 1.0) return false;
	morphAndMergeSubmaps(correction.poses);
	return true;
}

void CSubmappedOccupancyGrid3D::writeOutputs(maps::MapOutputFolder& out, const std::string& suffix) const
{
	const std::string stem = "map_3d" + suffix;
	out.write(stem + ".bt", [&](const std::string& p) { saveAsOctomapBinary(p, out.frame()); });
	out.write(stem + ".ply", [&](const std::string& p) { saveOccupiedAsPly(p, out.frame()); });
	out.write(stem + ".bin", [&](const std::string& p) { core::saveGzAtomically(*this, p); });
}

std::string CSubmappedOccupancyGrid3D::summaryJsonFields() const
{
	std::ostringstream o;
	o << "\"submaps\": " << numSubmaps() << ", \"memory_bytes\": " << memoryBytes() << ", \"keyframes\": " << keyframes().size();
	return o.str();
}

}  // namespace keygrid
