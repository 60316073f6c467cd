#include <keygrid/core/ProgressBar.h>
#include <keygrid/core/TimestampAssociation.h>
#include <keygrid/sim/Renderer.h>
#include <keygrid/sim/Scene.h>
#include <keygrid/slam/apps/KeyFrameViews.h>
#include <mrpt/system/filesystem.h>

#include <stdexcept>

namespace keygrid::slam
{
std::size_t renderKeyFrameViews(const KeyFrameViewsOptions& o, const core::Trajectory& gtTraj, const KeyFrameViewFn& view)
{
	if (!mrpt::system::fileExists(o.scenePath)) throw std::runtime_error("scene file '" + o.scenePath + "' does not exist");
	const sim::Scene scene = sim::Scene::loadFromFile(o.scenePath);
	const core::Trajectory kfs = core::readTumTrajectory(o.keyframesPath);
	std::vector<double> tk, tg;
	for (const auto& k : kfs) tk.push_back(k.t);
	for (const auto& g : gtTraj) tg.push_back(g.t);
	const auto matches = core::associateTimestamps(tk, tg, o.maxDt);
	if (matches.empty())
		throw std::runtime_error(
			"no keyframe of '" + o.keyframesPath + "' has a ground-truth pose within " + std::to_string(o.maxDt) + " s");
	const sim::Renderer renderer(scene);
	sim::RenderOutput rendered;
	core::ProgressBar bar("visibility", matches.size(), o.progress);
	std::size_t done = 0;
	for (const auto& [ik, ig] : matches)
	{
		const auto& T_world_cam = gtTraj[ig].T_world_cam;
		renderer.render(T_world_cam, gtTraj[ig].t - scene.options.startTime, rendered);
		view(rendered.depth, scene.camera, T_world_cam);
		bar.update(++done);
	}
	bar.finish();
	return matches.size();
}

}  // namespace keygrid::slam
