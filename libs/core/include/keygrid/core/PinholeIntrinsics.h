#pragma once
/** \file PinholeIntrinsics.h
 * The pinhole model of an undistorted image, and the one definition of back-projection:
 * pixel (u, v) with depth d (the point's z) -> optical-frame point (x right, y down, z forward)
 *     x = (u - cx) / fx * d,   y = (v - cy) / fy * d,   z = d,
 * i.e. the normalised ray ((u - cx) / fx, (v - cy) / fy, 1) scaled by d.
 *
 * core::RgbdCamera describes the sensor (image size, distortion, depth unit, name) and converts
 * to this in one place (RgbdCamera::pinhole()); what works on undistorted pixels (the frontend's
 * keypoints, the maps' depth images) keeps only these four numbers, cheap to copy into every
 * cost functor (sfm::PinholeIntrinsics is this type).
 *
 * Loops over an image precompute rayX per column and rayY per row; each coordinate is then
 * ray * d, the same operations in the same order as backProject().
 */
#include <Eigen/Core>

namespace keygrid::core
{
/** Focal lengths and principal point [px] in scalar type T: double, or float where a map's
 * inner loop works in float. */
template <typename T>
struct BasicPinholeIntrinsics
{
	T fx{525}, fy{525}, cx{319.5}, cy{239.5};

	/** x of the ray through column u on the plane z = 1: (u - cx) / fx */
	T rayX(T u) const { return (u - cx) / fx; }
	/** y of the ray through row v on the plane z = 1: (v - cy) / fy */
	T rayY(T v) const { return (v - cy) / fy; }
	/** The ray through pixel (u, v) on the plane z = 1 */
	Eigen::Matrix<T, 3, 1> ray(T u, T v) const { return {rayX(u), rayY(v), T(1)}; }
	/** The optical-frame point seen at pixel (u, v) at depth d (its z) [m] */
	Eigen::Matrix<T, 3, 1> backProject(T u, T v, T d) const { return {rayX(u) * d, rayY(v) * d, d}; }

	/** The same intrinsics in another scalar type (each value converted by static_cast). */
	template <typename U>
	BasicPinholeIntrinsics<U> cast() const
	{
		return {static_cast<U>(fx), static_cast<U>(fy), static_cast<U>(cx), static_cast<U>(cy)};
	}
};

using PinholeIntrinsics = BasicPinholeIntrinsics<double>;

}  // namespace keygrid::core
