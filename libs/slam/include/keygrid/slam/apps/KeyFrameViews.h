#pragma once
/** \file KeyFrameViews.h
 * What the keyframe cameras saw of a simulated scene: each keyframe of a run (keygrid-slam's
 * keyframes.txt) rendered noise-free at its ground-truth pose. keygrid-eval's map modes build
 * their visibility masks from these views (the 2D plan's seen cells, the 3D truth's seen voxels).
 */
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/core/TumTrajectory.h>
#include <mrpt/poses/CPose3D.h>
#include <opencv2/core/mat.hpp>

#include <functional>
#include <string>

namespace keygrid::slam
{
struct KeyFrameViewsOptions
{
	/** Scene INI the ground truth was rendered from */
	std::string scenePath;
	/** TUM file whose timestamps are the keyframes (keygrid-slam's keyframes.txt) */
	std::string keyframesPath;
	/** Largest |t_keyframe - t_gt| for a keyframe's ground-truth pose [s] (Default: 0.02 s) */
	double maxDt{0.02};
	/** Progress bar while rendering (Default: false) */
	bool progress{false};
};

/** One rendered view: depth (CV_32FC1, metres along the optical axis, 0 = no return) of the
 * scene's camera at T_world_cam (optical frame, ground-truth world). */
using KeyFrameViewFn =
	std::function<void(const cv::Mat& depth, const core::RgbdCamera& cam, const mrpt::poses::CPose3D& T_world_cam)>;

/** Renders every keyframe with a ground-truth pose within maxDt and calls `view` on it; returns
 * how many. Throws std::runtime_error on a missing scene or when no keyframe has a pose. */
std::size_t renderKeyFrameViews(const KeyFrameViewsOptions& opts, const core::Trajectory& gt, const KeyFrameViewFn& view);

}  // namespace keygrid::slam
