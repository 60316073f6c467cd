/** \file CSubmappedOccupancyGrid3D_insert.cpp
 * Integration of depth frames and MRPT observations; the observation likelihood.
 */
#include "detail/DepthOfScan.h"

#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

using namespace keygrid;

void CSubmappedOccupancyGrid3D::checkNewFrame(const char* caller, std::optional<uint64_t> keyframeId, double travelled) const
{
	if (keyframeId && m_keyframes.count(*keyframeId))
		throw std::invalid_argument(
			std::string(caller) + ": keyframe id " + std::to_string(*keyframeId) + " already inserted");
	if (!std::isfinite(travelled) || travelled < 0)
		throw std::invalid_argument(
			std::string(caller) + ": travelled = " + std::to_string(travelled) + " must be >= 0 m");
}

CSubmappedOccupancyGrid3D::InsertResult CSubmappedOccupancyGrid3D::insertDepthFrame(
	const cv::Mat& depth_m, const core::RgbdCamera& cam, const mrpt::poses::CPose3D& T_world_cam,
	double travelled, std::optional<uint64_t> keyframeId)
{
	checkNewFrame("insertDepthFrame", keyframeId, travelled);
	insertionOptions.conflict.validate();
	const FrameVoxelUpdates upd = integrator().castFrame(depth_m, cam, T_world_cam, m_resolution);
	std::optional<KeyframeRecord> record;
	if (keyframeId)
	{
		record.emplace();
		record->id = *keyframeId;
		record->T_world_cam = T_world_cam;
		record->travelled = travelled;
		record->camera = cam;
		if (insertionOptions.storeKeyframeDepth) record->depth = depth_m.clone();
	}
	return integrateFrame(upd, travelled, std::move(record));
}

CSubmappedOccupancyGrid3D::InsertResult CSubmappedOccupancyGrid3D::insertMapPoints(
	uint64_t keyframeId, const mrpt::poses::CPose3D& T_world_cam,
	const std::vector<mrpt::math::TPoint3D>& points_world, const core::RgbdCamera& cam, double travelled)
{
	checkNewFrame("insertMapPoints", keyframeId, travelled);
	insertionOptions.conflict.validate();
	KeyframeRecord k;
	k.id = keyframeId;
	k.T_world_cam = T_world_cam;
	k.travelled = travelled;
	k.camera = cam;
	k.fromMapPoints = true;
	std::vector<mrpt::math::TPoint3Df> ends;
	ends.reserve(points_world.size());
	for (const auto& p : points_world) ends.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z));
	k.points_cam = maps::toCameraFrame(T_world_cam, points_world);
	const FrameVoxelUpdates upd = integrator().castPoints(T_world_cam.translation(), ends, m_resolution);
	return integrateFrame(upd, travelled, std::move(k));
}

CSubmappedOccupancyGrid3D::InsertResult CSubmappedOccupancyGrid3D::integrateFrame(
	const FrameVoxelUpdates& upd, double travelled, std::optional<KeyframeRecord> record)
{
	m_modeMachine.setOptions(insertionOptions.conflict);
	InsertResult r;
	r.rays = upd.rays;
	r.voxelVisits = upd.voxelVisits;
	r.evidence = evaluateFrame(m_submaps[m_active].grid, upd, travelled,
		insertionOptions.conflict, insertionOptions.integration.threads);
	const MappingModeMachine::Decision d = m_modeMachine.step(r.evidence);
	r.mode = d.mode;
	r.reason = d.reason;
	// The first frame of an empty submap cannot conflict with it.
	if (d.conflict && m_submaps[m_active].grid.numBlocks() > 0)
	{
		r.conflict = true;
		Submap s(m_resolution);
		s.anchorKeyframe = record ? record->id : m_lastKeyframe.value_or(0);
		m_submaps.push_back(std::move(s));
		m_active = m_submaps.size() - 1;
	}
	integrator().apply(m_submaps[m_active].grid, upd, travelled);
	r.submap = m_active;

	if (record)
	{
		record->submap = m_active;
		Submap& s = m_submaps[m_active];
		if (s.keyframes.empty() && !r.conflict) s.anchorKeyframe = record->id;
		s.keyframes.push_back(record->id);
		m_lastKeyframe = record->id;
		const uint64_t id = record->id;
		m_keyframes.emplace(id, std::move(*record));
	}
	return r;
}

bool CSubmappedOccupancyGrid3D::insertDepthScan(
	const mrpt::obs::CObservation3DRangeScan& scan, const mrpt::poses::CPose3D& T_world_cam)
{
	cv::Mat depth;
	core::RgbdCamera cam;
	if (!detail::depthOfScan(scan, depth, cam)) return false;

	if (m_lastObsCamPose) m_obsTravelled += T_world_cam.distanceTo(*m_lastObsCamPose);
	m_lastObsCamPose = T_world_cam;

	std::optional<uint64_t> id;
	if (insertionOptions.observationsAreKeyframes)
	{
		while (m_keyframes.count(m_nextObsKeyframeId)) ++m_nextObsKeyframeId;
		id = m_nextObsKeyframeId++;
	}
	insertDepthFrame(depth, cam, T_world_cam, m_obsTravelled, id);
	return true;
}

double CSubmappedOccupancyGrid3D::depthScanLikelihood(
	const mrpt::obs::CObservation3DRangeScan& scan, const mrpt::poses::CPose3D& T_world_cam) const
{
	// log p(z | m) = sum over decimated pixels of log P(voxel at the measured point occupied),
	// unknown voxels count 0.5, every probability floored at minProbability.
	cv::Mat depth;
	core::RgbdCamera cam;
	if (!detail::depthOfScan(scan, depth, cam)) return 0.0;
	const unsigned dec = likelihoodOptions.decimation;
	const double pMin = likelihoodOptions.minProbability;
	const core::PinholeIntrinsics K = cam.pinhole();
	double logLik = 0;
	for (int r = 0; r < depth.rows; r += static_cast<int>(dec))
		for (int c = 0; c < depth.cols; c += static_cast<int>(dec))
		{
			const float z = depth.at<float>(r, c);
			if (!(z > 0)) continue;
			const Eigen::Vector3d p_cam = K.backProject(c, r, z);
			const mrpt::math::TPoint3D pc(p_cam.x(), p_cam.y(), p_cam.z());
			if (pc.norm() > likelihoodOptions.maxRange) continue;
			const auto L = logOddsAt(T_world_cam.composePoint(pc));
			const double p = L ? 1.0 / (1.0 + std::exp(-double(*L))) : 0.5;
			logLik += std::log(std::max(pMin, p));
		}
	return logLik;
}
