#pragma once
/** \file Triangulation.h
 * Two-view triangulation of a point from undistorted pixels and known camera poses.
 */
#include <keygrid/sfm/RgbdReprojectionCost.h>
#include <mrpt/poses/CPose3D.h>

#include <Eigen/Core>

namespace keygrid::sfm
{
/** Linear (DLT) triangulation. With P_i = K [R_i | t_i] (T_cam_world of view i) and pixel
 * (u_i, v_i), each view gives two rows u_i P_i^3 - P_i^1 and v_i P_i^3 - P_i^2 of A; the point
 * is the right singular vector of A for the smallest singular value (homogeneous, then
 * dehomogenised). Returns false when the solution is at infinity or behind either camera. */
bool triangulateDlt(
	const mrpt::poses::CPose3D& T_world_cam1, const Eigen::Vector2d& uv1,
	const mrpt::poses::CPose3D& T_world_cam2, const Eigen::Vector2d& uv2, const PinholeIntrinsics& K,
	Eigen::Vector3d& p_world);

/** Angle [rad] between the rays from the two camera centres to p_world (the parallax). */
double parallaxAngle(
	const mrpt::poses::CPose3D& T_world_cam1, const mrpt::poses::CPose3D& T_world_cam2,
	const Eigen::Vector3d& p_world);

}  // namespace keygrid::sfm
