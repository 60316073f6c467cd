#include "EvalScenes.h"

namespace keygrid::test
{
core::Trajectory writeSceneTrajectory(const sim::Scene& scene, const std::string& dir, std::size_t keyframeStride)
{
	core::Trajectory gt, kfs;
	for (std::size_t i = 0; i < scene.options.frames; i++)
	{
		gt.push_back({scene.timestamp(i), scene.cameraPose(i)});
		if (i % keyframeStride == 0) kfs.push_back(gt.back());
	}
	core::writeTumTrajectory(dir + "/gt.txt", gt);
	core::writeTumTrajectory(dir + "/kf.txt", kfs);
	return gt;
}

}  // namespace keygrid::test
