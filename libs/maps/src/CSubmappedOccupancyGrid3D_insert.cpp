/** \file CSubmappedOccupancyGrid3D_insert.cpp
 * Integration of depth frames and MRPT observations; the observation likelihood.
 */
#include "detail/DepthOfScan.h"

#include <keygrid/core/FrameConventions.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

using namespace keygrid;

CSubmappedOccupancyGrid3D::InsertResult CSubmappedOccupancyGrid3D::insertDepthFrame(
	const cv::Mat& depth_m, const core::RgbdCamera& cam, const mrpt::poses::CPose3D& T_world_cam,
	double travelled, std::optional<uint64_t> keyframeId)
{
	if (keyframeId && m_keyframes.count(*keyframeId))
		throw std::invalid_argument(
			"insertDepthFrame: keyframe id " + std::to_string(*keyframeId) + " already inserted");
	if (!std::isfinite(travelled) || travelled < 0)
		throw std::invalid_argument(
			"insertDepthFrame: travelled = " + std::to_string(travelled) + " must be >= 0 m");
	insertionOptions.conflict.validate();
	m_modeMachine.setOptions(insertionOptions.conflict);

	DepthFrameIntegrator& integ = integrator();
	const FrameVoxelUpdates upd = integ.castFrame(depth_m, cam, T_world_cam, m_resolution);

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
		s.anchorKeyframe = keyframeId ? *keyframeId : m_lastKeyframe.value_or(0);
		m_submaps.push_back(std::move(s));
		m_active = m_submaps.size() - 1;
	}
	integ.apply(m_submaps[m_active].grid, upd, travelled);
	r.submap = m_active;

	if (keyframeId)
	{
		KeyframeRecord k;
		k.id = *keyframeId;
		k.T_world_cam = T_world_cam;
		k.travelled = travelled;
		k.submap = m_active;
		k.camera = cam;
		if (insertionOptions.storeKeyframeDepth) k.depth = depth_m.clone();
		Submap& s = m_submaps[m_active];
		if (s.keyframes.empty() && !r.conflict) s.anchorKeyframe = k.id;
		s.keyframes.push_back(k.id);
		m_keyframes.emplace(k.id, std::move(k));
		m_lastKeyframe = *keyframeId;
	}
	return r;
}


bool CSubmappedOccupancyGrid3D::internal_insertObservation(
	const mrpt::obs::CObservation& obs, const std::optional<const mrpt::poses::CPose3D>& robotPose)
{
	const auto* scan = dynamic_cast<const mrpt::obs::CObservation3DRangeScan*>(&obs);
	if (!scan) return false;
	cv::Mat depth;
	core::RgbdCamera cam;
	if (!detail::depthOfScan(*scan, depth, cam)) return false;

	const mrpt::poses::CPose3D T_world_robot = robotPose ? *robotPose : mrpt::poses::CPose3D();
	const mrpt::poses::CPose3D T_world_cam =
		core::cameraPoseFromSensorPose(T_world_robot + scan->sensorPose);
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

bool CSubmappedOccupancyGrid3D::internal_canComputeObservationLikelihood(
	const mrpt::obs::CObservation& obs) const
{
	return dynamic_cast<const mrpt::obs::CObservation3DRangeScan*>(&obs) != nullptr;
}

double CSubmappedOccupancyGrid3D::internal_computeObservationLikelihood(
	const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& takenFrom) const
{
	// log p(z | m) = sum over decimated pixels of log P(voxel at the measured point occupied),
	// unknown voxels count 0.5, every probability floored at minProbability.
	const auto* scan = dynamic_cast<const mrpt::obs::CObservation3DRangeScan*>(&obs);
	if (!scan) return 0.0;
	cv::Mat depth;
	core::RgbdCamera cam;
	if (!detail::depthOfScan(*scan, depth, cam)) return 0.0;
	const mrpt::poses::CPose3D T_world_cam =
		core::cameraPoseFromSensorPose(takenFrom + scan->sensorPose);
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
