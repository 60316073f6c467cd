/** \file CSubmappedOccupancyGrid3D_morph.cpp
 * Trajectory correction: grid morphing + merging (the paper's method) and the full
 * re-integration baseline.
 */
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <mrpt/system/CTicTac.h>

#include <stdexcept>

using namespace keygrid;

MorphKeyframe CSubmappedOccupancyGrid3D::morphKeyframe(uint64_t id, const KeyframeRecord& rec, const mrpt::poses::CPose3D& T_world_cam_new)
{
	MorphKeyframe k;
	k.id = id;
	k.submap = rec.submap;
	k.travelled = rec.travelled;
	k.camera = rec.camera;
	k.T_world_cam_old = rec.T_world_cam;
	k.T_world_cam_new = T_world_cam_new;
	return k;
}

MorphingStats CSubmappedOccupancyGrid3D::morphAndMergeSubmaps(const TrajectoryCorrection& corr)
{
	std::vector<const VoxelBlockGrid*> sources;
	for (const auto& s : m_submaps) sources.push_back(&s.grid);

	std::vector<MorphKeyframe> kfs;
	kfs.reserve(m_keyframes.size());
	for (const auto& [id, rec] : m_keyframes)
	{
		const auto it = corr.find(id);
		kfs.push_back(morphKeyframe(id, rec, it != corr.end() ? it->second.T_world_cam_new : rec.T_world_cam));
	}

	MorphingStats stats;
	VoxelBlockGrid merged = morphAndMerge(sources, kfs, morphingOptions, &stats);

	Submap s(m_resolution);
	s.grid = std::move(merged);
	for (auto& [id, rec] : m_keyframes)
	{
		const auto it = corr.find(id);
		if (it != corr.end())
		{
			if (m_lastObsCamPose && rec.T_world_cam == *m_lastObsCamPose)
				m_lastObsCamPose = it->second.T_world_cam_new;
			rec.T_world_cam = it->second.T_world_cam_new;
		}
		rec.submap = 0;
		s.keyframes.push_back(id);
	}
	s.anchorKeyframe = m_keyframes.empty() ? 0 : m_keyframes.begin()->first;
	m_submaps.assign(1, std::move(s));
	m_active = 0;
	return stats;
}

CSubmappedOccupancyGrid3D::ReintegrationStats
	CSubmappedOccupancyGrid3D::reintegrateAtCorrectedPoses(const TrajectoryCorrection& corr)
{
	for (const auto& [id, rec] : m_keyframes)
		if (rec.depth.empty())
			throw std::logic_error(
				"reintegrateAtCorrectedPoses: keyframe " + std::to_string(id) +
				" has no stored depth (set insertionOptions.storeKeyframeDepth = true)");
	mrpt::system::CTicTac timer;
	ReintegrationStats st;
	DepthFrameIntegrator& integ = integrator();
	Submap s(m_resolution);
	for (auto& [id, rec] : m_keyframes)
	{
		const auto it = corr.find(id);
		if (it != corr.end()) rec.T_world_cam = it->second.T_world_cam_new;
		const FrameVoxelUpdates upd = integ.castFrame(rec.depth, rec.camera, rec.T_world_cam, m_resolution);
		integ.apply(s.grid, upd, rec.travelled);
		rec.submap = 0;
		s.keyframes.push_back(id);
		++st.frames;
	}
	s.anchorKeyframe = m_keyframes.empty() ? 0 : m_keyframes.begin()->first;
	m_submaps.assign(1, std::move(s));
	m_active = 0;
	st.seconds = timer.Tac();
	return st;
}

bool CSubmappedOccupancyGrid3D::builtFromMapPoints() const
{
	if (m_keyframes.empty()) return false;
	for (const auto& [id, rec] : m_keyframes)
		if (!rec.fromMapPoints) return false;
	return true;
}

CSubmappedOccupancyGrid3D::ReintegrationStats
	CSubmappedOccupancyGrid3D::rebuildFromMapPoints(
		const TrajectoryCorrection& corr, double worldScale, const std::map<uint64_t, std::vector<mrpt::math::TPoint3D>>& newPoints)
{
	if (!builtFromMapPoints())
		throw std::logic_error("rebuildFromMapPoints: the grid holds keyframes integrated from depth");
	mrpt::system::CTicTac timer;
	const auto scalePoints = [](std::vector<mrpt::math::TPoint3Df>& pts, double factor) {
		const float f = static_cast<float>(factor);
		for (auto& p : pts) p = mrpt::math::TPoint3Df(p.x * f, p.y * f, p.z * f);
	};
	ReintegrationStats st;
	DepthFrameIntegrator& integ = integrator();
	Submap s(m_resolution);
	std::vector<mrpt::math::TPoint3Df> ends;
	for (auto& [id, rec] : m_keyframes)
	{
		if (worldScale != 1.0)
		{
			scalePoints(rec.points_cam, worldScale);
			rec.T_world_cam.x(rec.T_world_cam.x() * worldScale);
			rec.T_world_cam.y(rec.T_world_cam.y() * worldScale);
			rec.T_world_cam.z(rec.T_world_cam.z() * worldScale);
			rec.travelled *= worldScale;
		}
		if (const auto it = corr.find(id); it != corr.end())
		{
			rec.T_world_cam = it->second.T_world_cam_new;
			if (it->second.scale != 1.0) scalePoints(rec.points_cam, it->second.scale);
		}
		if (const auto it = newPoints.find(id); it != newPoints.end()) rec.points_cam = maps::toCameraFrame(rec.T_world_cam, it->second);
		ends.clear();
		for (const auto& p : rec.points_cam)
		{
			const auto q = rec.T_world_cam.composePoint(mrpt::math::TPoint3D(p.x, p.y, p.z));
			ends.emplace_back(static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(q.z));
		}
		integ.apply(s.grid, integ.castPoints(rec.T_world_cam.translation(), ends, m_resolution), rec.travelled);
		rec.submap = 0;
		s.keyframes.push_back(id);
		++st.frames;
	}
	s.anchorKeyframe = m_keyframes.begin()->first;
	m_submaps.assign(1, std::move(s));
	m_active = 0;
	st.seconds = timer.Tac();
	return st;
}
