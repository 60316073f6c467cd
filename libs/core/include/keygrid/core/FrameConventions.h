#pragma once
/** \file FrameConventions.h
 * The single place where MRPT's depth-camera axes meet the optical axes keygrid uses.
 *
 * - "cam" (optical): x right, y down, z forward — the frame of TUM ground truth and OpenCV.
 * - MRPT CObservation3DRangeScan depth frame: +X forward, +Y left, +Z up.
 *
 * A point p_cam = (x, y, z) is p_mrpt = (z, -x, -y). The pose of the optical frame in the MRPT
 * depth frame is T_depth_cam = (0,0,0, yaw=-90deg, pitch=0, roll=-90deg), which is also
 * MRPT's default CObservation3DRangeScan::relativePoseIntensityWRTDepth for coinciding cameras.
 */
#include <mrpt/math/TPoint3D.h>
#include <mrpt/poses/CPose3D.h>

namespace keygrid::core
{
/** Pose of the optical ("cam") frame expressed in MRPT's depth-sensor frame. */
const mrpt::poses::CPose3D& T_depth_cam();

/** Point in the optical frame -> same point in MRPT's depth-sensor frame. */
mrpt::math::TPoint3D camToMrptDepth(const mrpt::math::TPoint3D& p_cam);
/** Point in MRPT's depth-sensor frame -> same point in the optical frame. */
mrpt::math::TPoint3D mrptDepthToCam(const mrpt::math::TPoint3D& p_depth);

/** Given the pose of MRPT's depth-sensor frame in the world, the optical camera pose:
 * T_world_cam = T_world_depth * T_depth_cam. */
mrpt::poses::CPose3D cameraPoseFromSensorPose(const mrpt::poses::CPose3D& T_world_depth);
/** Inverse of cameraPoseFromSensorPose: T_world_depth = T_world_cam * inv(T_depth_cam). */
mrpt::poses::CPose3D sensorPoseFromCameraPose(const mrpt::poses::CPose3D& T_world_cam);

}  // namespace keygrid::core
