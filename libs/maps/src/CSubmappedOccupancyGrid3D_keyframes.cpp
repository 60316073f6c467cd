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
	if (!kf.depth.empty())
		insertDepthFrame(kf.depth, kf.camera, kf.T_world_cam, kf.travelled, kf.id);
	else if (!kf.points_world.empty())
		insertMapPoints(kf.id, kf.T_world_cam, kf.points_world, kf.camera, kf.travelled);
}

bool CSubmappedOccupancyGrid3D::applyCorrection(const maps::MapCorrection& correction)
{
	const auto checkFactor = [](double f, const std::string& what) {
		if (!(f > 0) || !std::isfinite(f))
			throw std::invalid_argument("CSubmappedOccupancyGrid3D::applyCorrection: " + what + " " + std::to_string(f) + " is not a positive finite factor");
	};
	checkFactor(correction.scale, "scale");
	bool scaled = correction.scale != 1.0;
	for (const auto& [id, c] : correction.poses)
	{
		checkFactor(c.scale, "keyframe " + std::to_string(id) + " scale");
		scaled = scaled || (c.scale != 1.0 && m_keyframes.count(id));
	}
	// Map points are kept per keyframe: such a grid is rebuilt from them, in any scale.
	if (builtFromMapPoints())
	{
		rebuildFromMapPoints(correction.poses, correction.scale, correction.points_world);
		return true;
	}
	// Submaps of depth are morphed rigidly; a scale would need their voxels resampled, which
	// the grid does not do (a depth camera's map is metric: it never gets one).
	if (scaled && !keyframes().empty())
		throw std::invalid_argument(
			"CSubmappedOccupancyGrid3D::applyCorrection: cannot scale a grid built from depth (scale " +
			std::to_string(correction.scale) + ", " + std::to_string(keyframes().size()) + " keyframes)");
	if (scaled) return false;
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
