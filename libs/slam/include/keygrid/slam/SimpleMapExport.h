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
 *
 * The file is written streaming (writeKeyframesSimpleMap): one keyframe's images at a time are
 * loaded and serialized, the bytes being those CSimpleMap's own serialization gives.
 */
#include <keygrid/sfm/SparseMap.h>
#include <keygrid/slam/KeyFrameImageSource.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/serialization/CSerializable.h>

#include <string>

namespace keygrid::slam
{
/** The simple map entry of keyframe `kf` with its images `img` (both non-empty). The pose
 * covariance is zero: the SLAM system does not estimate marginal covariances. */
mrpt::maps::CSimpleMap::Pair keyframeSimpleMapEntry(const sfm::KeyFrame& kf, const KeyFrameImageData& img);

/** Builds, in RAM, the simple map of all keyframes of `map` that have depth and an image in
 * `images`. */
mrpt::maps::CSimpleMap keyframesSimpleMap(const sfm::SparseMap& map, const KeyFrameImageSource& images = KeyFrameImagesInRam());

/** Writes keyframesSimpleMap(map, images) to `path` (as core::saveGzAtomically would, byte for byte)
 * with the images of one keyframe at a time in RAM. Returns the number of entries. */
std::size_t writeKeyframesSimpleMap(const sfm::SparseMap& map, const KeyFrameImageSource& images, const std::string& path);

}  // namespace keygrid::slam
