#pragma once
/** \file EvalScenes.h
 * Inputs of keygrid-eval's map-mode tests: a shipped scene's ground-truth camera path and
 * keyframes, written as TUM files.
 */
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/sim/Scene.h>

#include <string>

namespace keygrid::test
{
/** Writes the scene's camera pose at every frame to dir/gt.txt and every `keyframeStride`-th of
 * them to dir/kf.txt; returns the whole path. */
core::Trajectory writeSceneTrajectory(const sim::Scene& scene, const std::string& dir, std::size_t keyframeStride = 50);

}  // namespace keygrid::test
