/** \file CISMOccupancyGrid2D_keyframes.cpp
 * CISMOccupancyGrid2D in a SLAM run (maps::KeyFrameMap): keyframe input, the run's floor
 * frame, corrections, outputs and summary.
 */
#include <keygrid/core/AtomicOutput.h>
#include <keygrid/maps/CISMOccupancyGrid2D.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace keygrid
{
void CISMOccupancyGrid2D::insertKeyFrame(const maps::MapKeyFrame& kf, const maps::KeyFrameFeed& feed)
{
	if (feed.gridInput == maps::GridInput::Depth && !kf.depth.empty())
	{
		// Dense input is reduced in the floor frame: it waits for the floor.
		if (!floorKnown())
		{
			m_waitingForFloor.push_back(kf.id);
			return;
		}
		for (uint64_t id : m_waitingForFloor)
			if (const auto earlier = feed.keyFrame(id)) insertKeyframeDepth(id, earlier->T_world_cam, earlier->depthScan());
		m_waitingForFloor.clear();
		insertKeyframeDepth(kf.id, kf.T_world_cam, kf.depthScan());
		return;
	}
	// Sparse input is stored also before the floor is known, and integrated then.
	insertKeyframePoints(kf.id, kf.T_world_cam, kf.points_world);
}

bool CISMOccupancyGrid2D::applyCorrection(const maps::MapCorrection& correction)
{
	const auto checkFactor = [](double f, const std::string& what) {
		if (!(f > 0) || !std::isfinite(f))
			throw std::invalid_argument("CISMOccupancyGrid2D::applyCorrection: " + what + " " + std::to_string(f) + " is not a positive finite factor");
	};
	checkFactor(correction.scale, "scale");
	for (const auto& [id, c] : correction.poses) checkFactor(c.scale, "keyframe " + std::to_string(id) + " scale");
	const auto scaleRays = [](KeyframeRays& kf, double factor) {
		const float s = static_cast<float>(factor);
		for (auto& p : kf.points_cam) p = mrpt::math::TPoint3Df(p.x * s, p.y * s, p.z * s);
	};
	// A rescaled world: the stored rays (camera frame) and every pose's translation scale
	// with it, also those of keyframes stored before the floor frame was known.
	if (correction.scale != 1.0)
		for (auto& [id, kf] : m_keyframes)
		{
			scaleRays(kf, correction.scale);
			kf.T_world_cam.x(kf.T_world_cam.x() * correction.scale);
			kf.T_world_cam.y(kf.T_world_cam.y() * correction.scale);
			kf.T_world_cam.z(kf.T_world_cam.z() * correction.scale);
		}
	// A keyframe's own similarity (monocular loop correction): its rays grow with it.
	for (const auto& [id, c] : correction.poses)
		if (const auto it = m_keyframes.find(id); c.scale != 1.0 && it != m_keyframes.end()) scaleRays(it->second, c.scale);
	// Re-estimated map points replace a keyframe's stored rays, in its corrected camera frame.
	for (const auto& [id, pts] : correction.points_world)
	{
		const auto it = m_keyframes.find(id);
		if (it == m_keyframes.end()) continue;
		const auto c = correction.poses.find(id);
		const mrpt::poses::CPose3D& T = c != correction.poses.end() ? c->second.T_world_cam_new : it->second.T_world_cam;
		it->second.points_cam = maps::toCameraFrame(T, pts);
	}
	if (correction.T_world_floor) setExternalFloorPose(*correction.T_world_floor);
	if (!floorKnown()) return false;  // nothing integrated yet: no floor frame
	std::map<uint64_t, mrpt::poses::CPose3D> newPoses;
	for (const auto& [id, c] : correction.poses)
		if (m_keyframes.count(id)) newPoses[id] = c.T_world_cam_new;
	applyTrajectoryCorrection(newPoses);
	return true;
}

void CISMOccupancyGrid2D::setFloorFrame(const std::optional<mrpt::poses::CPose3D>& T_world_floor)
{
	// A floor pose of the grid's own would be silently replaced: refused, naming where the
	// floor of a SLAM run is given.
	const auto& io = insertionOptions;
	if (!m_floorExternal && !io.estimateFloorFromDepth && !maps::ExportFrame{io.T_world_floor, {}}.isIdentity())
		throw std::invalid_argument(
			"[" + (m_optionSection.empty() ? std::string("ismOccupancyGrid2D") : m_optionSection) +
			"_insertOpts] T_world_floor: keygrid-slam gives every map the run's one floor frame; set it as "
			"[floor] T_world_floor instead");
	if (!T_world_floor)
	{
		expectExternalFloorPose();
		return;
	}
	// Re-integrating every keyframe costs as much as the whole map; a floor estimate that
	// moves the grid by less than floorReanchorShift is not worth it.
	// (Sparse keyframes stored before the first floor frame are integrated now.)
	if (floorKnown() && !m_keyframes.empty() && floorFrameShift(*T_world_floor) <= io.floorReanchorShift) return;
	setExternalFloorPose(*T_world_floor);
	if (!m_keyframes.empty()) applyTrajectoryCorrection({});
}

/* A point q of the grid's box (old floor frame) has coordinates D q = R q + t in the new
 * frame, D = inv(T_world_floor_new) (+) T_world_floor_old. Its move |(R - I) q + t| is a
 * convex function of q, so the largest move over the box is at one of its eight corners. */
double CISMOccupancyGrid2D::floorFrameShift(const mrpt::poses::CPose3D& T_world_floor) const
{
	const mrpt::poses::CPose3D D = floorPose() - T_world_floor;  // a - b = inv(b) (+) a
	const double zs[2] = {-insertionOptions.floorTolerance, insertionOptions.obstacleMaxHeight};
	double largest = 0;
	for (const double x : {xMin(), xMax()})
		for (const double y : {yMin(), yMax()})
			for (const double z : zs)
			{
				const mrpt::math::TPoint3D q(x, y, z);
				largest = std::max(largest, (D.composePoint(q) - q).norm());
			}
	return largest;
}

void CISMOccupancyGrid2D::writeOutputs(maps::MapOutputFolder& out, const std::string& suffix) const
{
	const std::string stem = "map_2d" + suffix;
	// Each file appears atomically; the .pgm is written first, beside the .yaml.
	if (out.write(stem + ".yaml", [&](const std::string& p) { saveAsRosMapServer(p); })) out.noteWritten(stem + ".pgm");
	out.write(stem + ".png", [&](const std::string& p) { saveAsImage(p); });
	out.write(stem + ".bin", [&](const std::string& p) { core::saveGzAtomically(*this, p); });
}

std::string CISMOccupancyGrid2D::summaryJsonFields() const
{
	const auto c = countStates();
	std::ostringstream o;
	o << "\"cells\": " << sizeX() * sizeY() << ", \"states\": [" << c[0] << ", " << c[1] << ", " << c[2]
	  << "], \"keyframes\": " << m_keyframes.size();
	return o.str();
}

}  // namespace keygrid
