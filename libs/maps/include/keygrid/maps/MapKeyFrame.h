#pragma once
/** \file MapKeyFrame.h
 * A keyframe as keygrid's maps take it (maps::KeyFrameMap::insertKeyFrame): its pose, camera,
 * depth, map points and the camera's path length. keygrid-slam builds one from its sparse map;
 * the maps library does not depend on the frontend, so this is all a map sees of a keyframe.
 */
#include <keygrid/core/RgbdCamera.h>
#include <mrpt/math/TPoint3D.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose3D.h>
#include <opencv2/core/mat.hpp>

#include <cstdint>
#include <vector>

namespace keygrid::maps
{
class MapKeyFrame
{
   public:
	/** The keyframe's id in the sparse map; maps record what they integrated under it. */
	uint64_t id{0};
	/** Pose of the optical frame (x right, y down, z forward) in the SLAM world, as the sparse
	 * map holds it now. */
	mrpt::poses::CPose3D T_world_cam;
	/** The camera of the depth image (intrinsics, depth units). */
	core::RgbdCamera camera;
	/** Depth [m] (CV_32FC1, 0 = no reading); empty when the keyframe has none (monocular). */
	cv::Mat depth;
	/** The keyframe's map points (the landmarks it observes), in the world [m]. */
	std::vector<mrpt::math::TPoint3D> points_world;
	/** Length of the camera's path up to this keyframe [m]. */
	double travelled{0};

	/** `depth` as an MRPT observation, for maps that integrate CObservation3DRangeScan: MRPT's
	 * depth frame, the range image quantized to camera.depthUnits (0 where the depth does not
	 * fit 16 bits), sensor pose identity, maxRange 10 m. Built on the first call and shared by
	 * every map the keyframe goes to; its range image is 0x0 when `depth` is empty. */
	const mrpt::obs::CObservation3DRangeScan& depthScan() const;

   private:
	mutable mrpt::obs::CObservation3DRangeScan::Ptr m_depthScan;
};

/** World points in the optical frame of a camera at T_world_cam (what the grids store of a
 * keyframe's map points). */
std::vector<mrpt::math::TPoint3Df> toCameraFrame(
	const mrpt::poses::CPose3D& T_world_cam, const std::vector<mrpt::math::TPoint3D>& points_world);

}  // namespace keygrid::maps
