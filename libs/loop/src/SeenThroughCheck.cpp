#include <keygrid/loop/SeenThroughCheck.h>

#include <cmath>
#include <set>

namespace keygrid::loop
{
namespace
{
/** Landmarks at most this far in front of the target camera [m], or behind it, are not
 * compared: closer than any depth camera measures, and near the camera plane the projection
 * is ill-conditioned. */
constexpr double kMinLandmarkDepth = 0.1;
}  // namespace

SeenThroughCount countSeenThrough(
	const sfm::SparseMap& map, const std::vector<sfm::KeyFrameId>& sources, const Eigen::Isometry3d& T_target_points,
	const sfm::KeyFrame& target, const sfm::PinholeIntrinsics& K, float radiusPx, double relTolerance, double absTolerance)
{
	std::set<sfm::LandmarkId> landmarks;
	for (const auto id : sources)
		if (map.hasKeyFrame(id))
			for (const auto l : map.keyframe(id).landmarks)
				if (l != sfm::kNoLandmark && map.hasLandmark(l)) landmarks.insert(l);
	const auto& f = target.features;
	SeenThroughCount out;
	std::vector<int> near;
	for (const auto l : landmarks)
	{
		const Eigen::Vector3d p = T_target_points * map.landmark(l).p_world;
		if (p.z() <= kMinLandmarkDepth) continue;
		const double u = K.fx * p.x() / p.z() + K.cx, v = K.fy * p.y() / p.z() + K.cy;
		if (u < 0 || v < 0 || u >= f.camera.width || v >= f.camera.height) continue;
		f.featuresInArea(static_cast<float>(u), static_cast<float>(v), radiusPx, -1, -1, near);
		int best = -1;
		double bestD2 = 0;
		for (const int i : near)
		{
			if (!(f.depth[i] > 0)) continue;
			const double du = f.undistorted[i].x - u, dv = f.undistorted[i].y - v, d2 = du * du + dv * dv;
			if (best < 0 || d2 < bestD2) best = i, bestD2 = d2;
		}
		if (best < 0) continue;
		const double measured = f.depth[best], tolerance = relTolerance * p.z() + absTolerance;
		if (std::abs(measured - p.z()) <= tolerance)
			out.agreeing++;
		else if (measured > p.z() + tolerance)
			out.seenThrough++;
	}
	return out;
}

}  // namespace keygrid::loop
