/** \file MapKeyFrame.cpp
 * MapKeyFrame::depthScan(): the keyframe's depth as a CObservation3DRangeScan; map points in
 * a keyframe's camera frame.
 */
#include <keygrid/core/FrameConventions.h>
#include <keygrid/maps/MapKeyFrame.h>

#include <cmath>

namespace keygrid::maps
{
const mrpt::obs::CObservation3DRangeScan& MapKeyFrame::depthScan() const
{
	if (m_depthScan) return *m_depthScan;
	auto obs = mrpt::obs::CObservation3DRangeScan::Create();
	obs->hasRangeImage = true;
	obs->range_is_depth = true;
	obs->rangeUnits = camera.depthUnits;
	obs->rangeImage.resize(depth.rows, depth.cols);
	for (int r = 0; r < depth.rows; r++)
		for (int c = 0; c < depth.cols; c++)
		{
			const double q = std::round(depth.at<float>(r, c) / camera.depthUnits);
			obs->rangeImage(r, c) = q > 0 && q < 65535 ? static_cast<uint16_t>(q) : 0;
		}
	obs->cameraParams = camera.toTCamera();
	obs->cameraParamsIntensity = obs->cameraParams;
	obs->relativePoseIntensityWRTDepth = core::T_depth_cam();
	obs->maxRange = 10.0f;
	m_depthScan = obs;
	return *m_depthScan;
}

std::vector<mrpt::math::TPoint3Df> toCameraFrame(
	const mrpt::poses::CPose3D& T_world_cam, const std::vector<mrpt::math::TPoint3D>& points_world)
{
	std::vector<mrpt::math::TPoint3Df> out;
	out.reserve(points_world.size());
	for (const auto& p : points_world)
	{
		const auto q = T_world_cam.inverseComposePoint(p);
		out.emplace_back(static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(q.z));
	}
	return out;
}

}  // namespace keygrid::maps
