#include <keygrid/sim/SceneObject.h>

#include <algorithm>

namespace keygrid::sim
{
bool ObjectMotion::visibleAt(double t) const
{
	if (visible.empty()) return true;
	for (const auto& [t0, t1] : visible)
		if (t >= t0 && t < t1) return true;
	return false;
}

PathKey ObjectMotion::at(double t) const
{
	if (t <= path.front().t) return path.front();
	if (t >= path.back().t) return path.back();
	const auto it = std::upper_bound(
		path.begin(), path.end(), t, [](double v, const PathKey& k) { return v < k.t; });
	const PathKey& b = *it;
	const PathKey& a = *(it - 1);
	const double s = (t - a.t) / (b.t - a.t);
	PathKey k;
	k.t = t;
	k.position = a.position + s * (b.position - a.position);
	k.yaw = a.yaw + s * (b.yaw - a.yaw);
	return k;
}

Eigen::Isometry3d SceneObject::poseAt(double t) const
{
	if (!dynamic || motion.path.empty()) return T_world_obj;
	const PathKey k = motion.at(t);
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	T.linear() = Eigen::AngleAxisd(k.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
				 T_world_obj.linear();
	T.translation() = k.position;
	return T;
}

}  // namespace keygrid::sim
