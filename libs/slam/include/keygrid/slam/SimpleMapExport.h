#pragma once
/** \file SimpleMapExport.h
 * keyframes.simplemap: the keyframes of a run as an mrpt::maps::CSimpleMap, so MRPT's own
 * tools can rebuild any map from them (`observations2map INI keyframes.simplemap PREFIX`,
 * with `LD_PRELOAD=libkeygrid_maps.so` for keygrid's map types) or browse them
 * (RawLogViewer, SceneViewer3D).
 *
 * Each entry is one keyframe, in id order: its final pose as a CPose3DPDFGaussian and a
 * CSensoryFrame with one CObservation3DRangeScan (core::makeRgbdObservation: depth, image,
 * intrinsics). MRPT's convention: the entry's pose is the robot pose and the observation's
 * sensorPose is relative to it. keygrid stores the sensor pose itself as the robot pose,
 * T_world_depth = core::sensorPoseFromCameraPose(T_world_cam), with sensorPose = identity.
 */
#include <keygrid/sfm/SparseMap.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/serialization/CSerializable.h>

#include <string>

namespace keygrid::slam
{
/** Builds the simple map of all keyframes of `map` that have depth and an image. The pose
 * covariance is zero: the SLAM system does not estimate marginal covariances. */
mrpt::maps::CSimpleMap keyframesSimpleMap(const sfm::SparseMap& map);

/** Serializes `obj` gz-compressed (as MRPT's tools expect for .simplemap, .3Dscene, ...) to
 * `path` atomically: written to `<path>.tmp`, then renamed. Throws std::runtime_error naming
 * the path on failure. */
void saveGzAtomically(const mrpt::serialization::CSerializable& obj, const std::string& path);

/** keyframesSimpleMap(map) saved with saveGzAtomically. Returns the number of entries. */
std::size_t writeKeyframesSimpleMap(const sfm::SparseMap& map, const std::string& path);

}  // namespace keygrid::slam
