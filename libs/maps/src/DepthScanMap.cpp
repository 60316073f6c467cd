/** \file DepthScanMap.cpp
 * DepthScanMap: MRPT's observation calls narrowed to depth scans at their camera pose.
 */
#include <keygrid/core/FrameConventions.h>
#include <keygrid/maps/DepthScanMap.h>

namespace keygrid::maps
{
bool DepthScanMap::internal_insertObservation(
	const mrpt::obs::CObservation& obs, const std::optional<const mrpt::poses::CPose3D>& robotPose)
{
	const auto* scan = dynamic_cast<const mrpt::obs::CObservation3DRangeScan*>(&obs);
	if (!scan) return false;
	const mrpt::poses::CPose3D T_world_robot = robotPose ? *robotPose : mrpt::poses::CPose3D();
	return insertDepthScan(*scan, core::cameraPoseFromSensorPose(T_world_robot + scan->sensorPose));
}

double DepthScanMap::internal_computeObservationLikelihood(
	const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& takenFrom) const
{
	const auto* scan = dynamic_cast<const mrpt::obs::CObservation3DRangeScan*>(&obs);
	if (!scan) return 0.0;
	return depthScanLikelihood(*scan, core::cameraPoseFromSensorPose(takenFrom + scan->sensorPose));
}

bool DepthScanMap::internal_canComputeObservationLikelihood(const mrpt::obs::CObservation& obs) const
{
	const auto* scan = dynamic_cast<const mrpt::obs::CObservation3DRangeScan*>(&obs);
	return scan != nullptr && canComputeDepthScanLikelihood(*scan);
}

}  // namespace keygrid::maps
