#pragma once
/** \file VectorAngle.h
 * The angle between two 3D vectors, atan2(|a x b|, a . b): accurate near 0 and pi, where
 * acos of the normalized dot product loses half its digits, and no normalization needed.
 */
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>

namespace keygrid::core
{
/** In [0, pi] [rad]; 0 when either vector is zero. */
inline double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }
}  // namespace keygrid::core
