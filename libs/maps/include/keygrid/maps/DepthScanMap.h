#pragma once
/** \file DepthScanMap.h
 * maps::DepthScanMap — the part of MRPT's CMetricMap contract that keygrid's three plugins
 * (CISMOccupancyGrid2D, CSubmappedOccupancyGrid3D, CHOCPointsMap) answer alike: they take
 * CObservation3DRangeScan observations and nothing else. Any other observation is not
 * inserted and has no likelihood; a depth scan goes on to the map with the pose of its
 * camera's optical frame (robot pose + sensorPose, converted by core::cameraPoseFromSensorPose,
 * the one place of that convention).
 */
#include <mrpt/maps/CMetricMap.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

#include <optional>

namespace keygrid::maps
{
class DepthScanMap : public mrpt::maps::CMetricMap
{
   protected:
	/** insertObservation() of a depth scan taken by the camera at T_world_cam: true when the
	 * map took it. */
	virtual bool insertDepthScan(const mrpt::obs::CObservation3DRangeScan& scan, const mrpt::poses::CPose3D& T_world_cam) = 0;
	/** Whether depthScanLikelihood() can score `scan`. */
	virtual bool canComputeDepthScanLikelihood(const mrpt::obs::CObservation3DRangeScan& scan) const = 0;
	/** Log-likelihood of `scan` taken by the camera at T_world_cam. */
	virtual double depthScanLikelihood(const mrpt::obs::CObservation3DRangeScan& scan, const mrpt::poses::CPose3D& T_world_cam) const = 0;

	bool internal_insertObservation(
		const mrpt::obs::CObservation& obs,
		const std::optional<const mrpt::poses::CPose3D>& robotPose = std::nullopt) final;
	double internal_computeObservationLikelihood(
		const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& takenFrom) const final;
	bool internal_canComputeObservationLikelihood(const mrpt::obs::CObservation& obs) const final;
};

}  // namespace keygrid::maps
