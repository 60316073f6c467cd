#include "LoopCorrection.h"

#include <keygrid/loop/LoopCloser.h>
#include <keygrid/loop/Sim3MapCorrection.h>

namespace keygrid::loop
{
std::map<sfm::KeyFrameId, Sim3> keyFrameSims(const sfm::SparseMap& map)
{
	std::map<sfm::KeyFrameId, Sim3> out;
	for (const auto& [id, kf] : map.keyframes()) out[id] = Sim3::fromIsometry(toIsometry(kf.T_world_cam));
	return out;
}

void applySim3Corrections(
	sfm::SparseMap& map, const std::map<sfm::KeyFrameId, Sim3>& oldS, const std::map<sfm::KeyFrameId, Sim3>& newS)
{
	for (const auto& [id, S] : newS) map.keyframe(id).T_world_cam = toCPose3D(S.rigid());
	detail::moveLandmarksWithKeyFrames(map, oldS, newS);
}

}  // namespace keygrid::loop
