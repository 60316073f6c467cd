#pragma once
/** \file Renderer.h
 * CPU ray caster of a Scene: one ray per pixel centre, tested only against the objects whose
 * projected bounding box covers the pixel (screen-space culling, near-plane clipped), nearest
 * hit wins. With the ray direction (u - cx)/fx, (v - cy)/fy, 1 in the optical frame, the ray
 * parameter of a hit IS its depth z: depth is exact up to double rounding.
 * Cameras with lens distortion (e.g. TUM fr1, for augmenting real sequences) get per-pixel
 * undistorted rays (x_n, y_n, 1) and no culling: slower, meant for few objects.
 * Shading: bilinear mip-mapped texture times Lambert (ambient + diffuse), view-independent so
 * features look the same from every viewpoint.
 */
#include <keygrid/sim/Scene.h>
#include <opencv2/core/mat.hpp>

#include <Eigen/Geometry>
#include <functional>
#include <vector>

namespace keygrid::sim
{
struct RenderOptions
{
	/** Worker threads (Default: 0 = all cores) */
	unsigned threads{0};
	/** Near clipping distance along the optical axis [m] (Default: 0.05) */
	double nearClip{0.05};
};

/** One rendered view (all images have the camera's size). */
struct RenderOutput
{
	cv::Mat colour;        //!< CV_8UC3 BGR, black where nothing is hit
	cv::Mat depth;         //!< CV_32FC1 depth along the optical axis [m], 0 where nothing is hit
	cv::Mat cosIncidence;  //!< CV_32FC1 |cos| of the angle between ray and surface normal
	cv::Mat objectIndex;   //!< CV_32SC1 index into Scene::objects, -1 where nothing is hit
};

class Renderer
{
   public:
	/** The scene must outlive the renderer (its camera is read at construction). */
	explicit Renderer(const Scene& scene, const RenderOptions& opts = {});

	/** Renders the scene at time t [s] seen from T_world_cam (optical frame). */
	void render(const Eigen::Isometry3d& T_world_cam, double t, RenderOutput& out) const;
	void render(const mrpt::poses::CPose3D& T_world_cam, double t, RenderOutput& out) const;
	/** A rolling-shutter camera: row y is rendered at time t_y = t + (y / H - 1/2) readout
	 * from poseAt(t_y), moving objects at t_y too (readout 0: render(poseAt(t), t, out)). */
	void renderRollingShutter(
		const std::function<Eigen::Isometry3d(double)>& poseAt, double t, double readout, RenderOutput& out) const;

	static Eigen::Isometry3d toIsometry(const mrpt::poses::CPose3D& p);

	/** An object prepared for one camera pose: its local frame seen from the camera. */
	struct PreparedObject
	{
		int object{-1};
		const Shape* shape{nullptr};
		Eigen::Matrix3d R_obj_cam;         //!< rotates optical-frame directions into the object frame
		Eigen::Vector3d o_obj;             //!< camera centre in the object frame
		Eigen::Vector3d n_light_obj;       //!< light direction in the object frame
		int x0{0}, x1{-1}, y0{0}, y1{-1};  //!< inclusive pixel rectangle that may be hit
	};

   private:
	/** The objects visible at time t, seen from T_world_cam, with their screen rectangles. */
	std::vector<PreparedObject> prepare(const Eigen::Isometry3d& T_world_cam, double t) const;
	/** Ray-casts and shades rows [r0, r1) of `out` against `objs`. */
	void renderRows(const std::vector<PreparedObject>& objs, int r0, int r1, RenderOutput& out) const;
	void allocate(RenderOutput& out) const;

	const Scene& m_scene;
	RenderOptions m_opts;
	/** Per-pixel normalised ray (x_n, y_n), row-major; only for distorted cameras. */
	std::vector<double> m_rays;
};

}  // namespace keygrid::sim
