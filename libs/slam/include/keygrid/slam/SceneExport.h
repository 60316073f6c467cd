#pragma once
/** \file SceneExport.h
 * scene.3Dscene: a run as an mrpt::opengl::COpenGLScene for SceneViewer3D
 * (`SceneViewer3D -l libkeygrid_maps.so scene.3Dscene`).
 *
 * Named objects (COpenGLViewport::getByName finds them):
 *  - "ground": CGridPlaneXY, 1 m cells, at display z = 0 (the floor when the run has a floor
 *    frame);
 *  - "keygrid_run": CSetOfObjects holding the next three, posed so that "up" is +Z on screen:
 *    inverse(T_world_floor) when the run has a floor frame (the display frame is then the
 *    floor frame of every other output), else core::T_depth_cam() (the first camera's
 *    optical axes shown as MRPT's x forward, z up);
 *  - "trajectory": CSetOfLines, a line strip through the camera centres of every frame
 *    (trajectory.txt), i.e. N poses -> N-1 consecutive segments (1 pose -> 1 null segment);
 *  - "keyframes": CSetOfObjects with one CFrustum per keyframe at its final pose;
 *  - "landmarks": CPointCloud of the sparse map points;
 *  - "map_<i>_<class>": CSetOfObjects with each metric map's getVisualizationInto(), moved to
 *    the same display frame (point clouds point by point, so colour-by-height means up).
 */
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/sfm/SparseMap.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/opengl/COpenGLScene.h>

#include <optional>
#include <string>

namespace keygrid::slam
{
/** Look of the exported scene (code-level settings, not INI). */
struct SceneExportOptions
{
	/** Depth of each keyframe frustum (distance to its far plane) [m] (Default: 0.15 m) */
	double frustumDepth{0.15};
	/** Point size of the sparse landmarks [px] (Default: 2) */
	float landmarkPointSize{2.0f};
	/** Width of the trajectory line [px] (Default: 3) */
	float trajectoryLineWidth{3.0f};
};

/** Builds the scene of a run: `trajectory` (every frame, T_world_cam), the keyframes and
 * landmarks of `map`, and every map of `maps` (may be null), shown in the floor frame
 * `T_world_floor` when given. */
mrpt::opengl::COpenGLScene::Ptr buildRunScene(
	const core::Trajectory& trajectory, const sfm::SparseMap& map,
	const mrpt::maps::CMultiMetricMap* maps, const std::optional<mrpt::poses::CPose3D>& T_world_floor,
	const SceneExportOptions& opts = {});

/** buildRunScene() saved gz-compressed to `path` atomically (temp file + rename). */
void writeRunScene(
	const core::Trajectory& trajectory, const sfm::SparseMap& map,
	const mrpt::maps::CMultiMetricMap* maps, const std::optional<mrpt::poses::CPose3D>& T_world_floor,
	const std::string& path, const SceneExportOptions& opts = {});

}  // namespace keygrid::slam
