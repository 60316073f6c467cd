#pragma once
/** \file HocGeometry.h
 * The bins of a Histogram of Oriented Cameras (HOC, source paper 2): k concentric spheres around
 * a map point, each approximated by an icosahedron (m = 20 faces, or 20 * 4^s after s
 * subdivisions). A camera centre c falls into bin (shell, face): the face is the one the ray
 * from the point towards c pierces, the shell the first sphere whose radius is >= |c - p|
 * (cameras beyond the largest radius count to the outermost shell).
 *
 * Face lookup. For the regular icosahedron all faces are tangent to one inner sphere, so the ray
 * with direction d pierces face f first iff d . n_f is maximal (n_f: unit face normal). A
 * subdivided face splits into 4 children whose vertices are the parent's vertices and the
 * edge midpoints pushed onto the unit sphere; the great-circle arc between two vertices passes
 * through their projected midpoint, so the children's spherical triangles tile the parent's
 * exactly and the lookup descends by the spherical-triangle test det(a, b, d) >= 0 on each edge.
 */
#include <Eigen/Core>

#include <array>
#include <vector>

namespace keygrid::maps
{
class HocGeometry
{
   public:
	/** radii: shell radii [m], strictly increasing, >= 1 of them; subdivisions: 0..3. Throws
	 * std::invalid_argument otherwise. */
	HocGeometry(std::vector<double> radii, int subdivisions);

	int numShells() const { return static_cast<int>(m_radii.size()); }
	int numFaces() const { return static_cast<int>(m_faces.size()); }
	int numBins() const { return numShells() * numFaces(); }
	const std::vector<double>& radii() const { return m_radii; }
	int subdivisions() const { return m_subdivisions; }

	/** Face pierced by direction d (need not be unit, must be non-zero). */
	int face(const Eigen::Vector3d& d) const;
	/** Shell of a camera at distance `dist` [m] from the point. */
	int shell(double dist) const;
	/** Bin of a camera centre seen from a point: shell * numFaces() + face; -1 when the camera
	 * coincides with the point. */
	int bin(const Eigen::Vector3d& point, const Eigen::Vector3d& cameraCentre) const;

	/** Unit direction through the centroid of face f. */
	Eigen::Vector3d faceCentre(int f) const;
	/** Unit vertices of face f, counter-clockwise seen from outside. */
	std::array<Eigen::Vector3d, 3> faceVertices(int f) const;
	/** The faces sharing an edge with f (always 3). */
	std::array<int, 3> faceNeighbours(int f) const;

   private:
	struct Face
	{
		std::array<int, 3> v;  //!< vertex indices, CCW from outside
	};
	std::vector<double> m_radii;
	int m_subdivisions{0};
	std::vector<Eigen::Vector3d> m_vertices;
	/** Faces of every level: level 0 = the icosahedron; children of face i of level l are
	 * 4i..4i+3 of level l+1. The bins are the faces of the finest level. */
	std::vector<std::vector<Face>> m_levels;
	std::vector<Face> m_faces;  //!< finest level (alias of m_levels.back())
	std::vector<Eigen::Vector3d> m_baseNormals;
	std::vector<std::array<int, 3>> m_neighbours;
};

}  // namespace keygrid::maps
