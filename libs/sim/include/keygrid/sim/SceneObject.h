#pragma once
/** \file SceneObject.h
 * One object of a scene: a shape, its texture, its pose in the world (z up) and, for dynamic
 * objects, how that pose and its visibility change with time.
 */
#include <keygrid/sim/Shape.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <utility>
#include <vector>

namespace keygrid::sim
{
/** A key of an object path: at time t [s from the sequence start] the object's centre is at
 * `position` [m] and it is turned by `yaw` [rad] about world z on top of its rest orientation. */
struct PathKey
{
	double t{0};
	Eigen::Vector3d position{0, 0, 0};
	double yaw{0};
};

/** Motion and visibility of a dynamic object. Positions and yaw are interpolated linearly
 * between keys and held before the first / after the last key. */
struct ObjectMotion
{
	std::vector<PathKey> path;  //!< sorted by t; empty: the object stays at its rest pose
	/** Half-open intervals [t0, t1) [s] during which the object exists; empty: always. */
	std::vector<std::pair<double, double>> visible;

	bool visibleAt(double t) const;
	/** Interpolated key at time t (path must be non-empty). */
	PathKey at(double t) const;
};

struct SceneObject
{
	std::string name;  //!< INI section suffix, e.g. "wall_north"
	Shape shape;
	/** Rest pose of the shape's local frame in the world */
	Eigen::Isometry3d T_world_obj{Eigen::Isometry3d::Identity()};
	/** Dynamic objects move / appear / vanish, are left out of ground-truth occupancy and are
	 * marked in the dynamic-pixel mask */
	bool dynamic{false};
	ObjectMotion motion;
	/** Index into Scene::textures */
	std::size_t texture{0};

	/** Pose of the local frame in the world at time t [s]. */
	Eigen::Isometry3d poseAt(double t) const;
	bool visibleAt(double t) const { return !dynamic || motion.visibleAt(t); }
};

}  // namespace keygrid::sim
