#pragma once
/** \file Shape.h
 * The simulator's solid primitives, each defined in its own local frame:
 * - Quad: the rectangle |x| <= a, |y| <= b of the plane z = 0 (two-sided);
 * - Box: |x| <= a, |y| <= b, |z| <= c;
 * - Cylinder: x^2 + y^2 <= r^2, |z| <= h (axis = local z, with caps).
 * Ray intersection, surface texture coordinates and surface sampling all work in that frame;
 * the caller moves rays into it.
 */
#include <Eigen/Core>

#include <array>
#include <functional>
#include <string>

namespace keygrid::sim
{
enum class ShapeType
{
	Quad,
	Box,
	Cylinder
};

/** "quad" / "box" / "cylinder"; throws std::invalid_argument on anything else. */
ShapeType shapeTypeFromString(const std::string& s);
std::string toString(ShapeType t);

/** A ray hit in the shape's local frame. */
struct LocalHit
{
	double t{0};   //!< ray parameter: hit = o + t d
	int face{-1};  //!< shape-specific face id (box: 0..5 = -x,+x,-y,+y,-z,+z; cylinder: 0 side, 1
				   //!< top, 2 bottom)
};

struct Shape
{
	ShapeType type{ShapeType::Box};
	/** Half extents: quad (a, b, -), box (a, b, c), cylinder (r, r, h) [m] */
	Eigen::Vector3d half{0.5, 0.5, 0.5};

	/** First hit with t in (tMin, tMax) of the ray o + t d (local frame, d need not be unit).
	 * Returns false when there is none. */
	bool intersect(
		const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tMin, double tMax,
		LocalHit& hit) const;

	/** Outward unit normal of `face` at local point p (quads: +z; the renderer flips it). */
	Eigen::Vector3d normal(const Eigen::Vector3d& p, int face) const;

	/** Texture coordinates [m] of local surface point p on `face`: distances along the surface,
	 * so a texture keeps its metric size on every face. */
	Eigen::Vector2d surfaceUV(const Eigen::Vector3d& p, int face) const;

	/** The 8 corners of the local bounding box. */
	std::array<Eigen::Vector3d, 8> boundingCorners() const;

	/** Calls f(p_local) for points covering the whole surface with spacing <= step [m],
	 * including every edge and corner (so axis-aligned faces are voxelised exactly). */
	void sampleSurface(double step, const std::function<void(const Eigen::Vector3d&)>& f) const;
};

}  // namespace keygrid::sim
