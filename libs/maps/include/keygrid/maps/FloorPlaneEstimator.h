#pragma once
/** \file FloorPlaneEstimator.h
 * RANSAC estimate of the floor plane from 3D points (depth or map points), for worlds that are
 * not gravity aligned (TUM). The floor is taken as the LOWEST large plane roughly perpendicular
 * to an "up" hint (a desk top is often larger in view than the floor) that lies below the camera.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/math/TPoint3D.h>
#include <mrpt/poses/CPose3D.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace keygrid::maps
{
struct FloorPlaneRansacOptions : public core::FieldTableOptions<FloorPlaneRansacOptions>
{
	/** Point-to-plane distance of an inlier [m] (Default: 0.02 m) */
	double inlierDistance{0.02};
	/** Least number of RANSAC hypotheses per plane; more are drawn when minInlierFraction needs
	 * them (N = log(0.01) / log(1 - f^3), at most 200 000) (Default: 300) */
	int iterations{300};
	/** Largest angle between the plane normal and the up hint [deg]. The hint is a camera's -y
	 * axis (or a mean of several), so this must cover how far the camera looks down: a
	 * hand-held camera aimed at the floor in front of it pitches 25-35 deg (Default: 40 deg) */
	double maxTiltDeg{40.0};
	/** Smallest inlier share of all points for a plane to count (Default: 0.10) */
	double minInlierFraction{0.10};
	/** The camera must be at least this high above the floor [m] (Default: 0.20 m) */
	double minCameraHeight{0.20};
	/** Random seed, so the estimate is reproducible (Default: 1) */
	uint32_t seed{1};

	/** INI keys prefixed with "floorRansac_" (they live in another struct's section). */
	core::OptionFields fields();
	/** Throws std::invalid_argument naming [section], key and value of the first bad field. */
	void validate(const std::string& section = "insertOpts") const;
};

/** Plane n . p + d = 0 with unit normal n pointing up (towards the camera). */
struct FloorPlane
{
	mrpt::math::TVector3D normal{0, 0, 1};
	double d{0};
	size_t inliers{0};
	/** Signed height of a point above the plane [m]. */
	double height(const mrpt::math::TPoint3D& p) const
	{
		return normal.x * p.x + normal.y * p.y + normal.z * p.z + d;
	}
};

/** Estimates the floor among `points_world`. `up_world` is a rough up direction (e.g. -y of
 * the optical camera frame) and `camera_world` the camera position. Returns nullopt when no
 * plane satisfies the options. The result is refined by least squares on its inliers. */
std::optional<FloorPlane> estimateFloorPlane(
	const std::vector<mrpt::math::TPoint3D>& points_world, const mrpt::math::TVector3D& up_world,
	const mrpt::math::TPoint3D& camera_world, const FloorPlaneRansacOptions& opts);

/** A floor frame for a plane: z = the plane normal, origin = the camera position projected on
 * the plane, x = `forward_world` projected on the plane (any perpendicular if degenerate). */
mrpt::poses::CPose3D floorPoseFromPlane(
	const FloorPlane& plane, const mrpt::math::TPoint3D& camera_world,
	const mrpt::math::TVector3D& forward_world);

}  // namespace keygrid::maps
