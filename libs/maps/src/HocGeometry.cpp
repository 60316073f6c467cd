/** \file HocGeometry.cpp
 * Icosahedron construction, subdivision and the bin lookup of the HOC descriptor.
 */
#include <keygrid/maps/HocGeometry.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

namespace keygrid::maps
{
namespace
{
double det3(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& d) { return a.cross(b).dot(d); }
}  // namespace

HocGeometry::HocGeometry(std::vector<double> radii, int subdivisions) : m_radii(std::move(radii)), m_subdivisions(subdivisions)
{
	if (m_radii.empty()) throw std::invalid_argument("HOC radii: at least one shell radius is needed");
	for (std::size_t i = 0; i < m_radii.size(); i++)
		if (!(m_radii[i] > 0) || !std::isfinite(m_radii[i]) || (i > 0 && !(m_radii[i] > m_radii[i - 1])))
			throw std::invalid_argument("HOC radii: must be finite, > 0 and strictly increasing (radius " + std::to_string(i) + " = " + std::to_string(m_radii[i]) + ")");
	if (subdivisions < 0 || subdivisions > 3)
		throw std::invalid_argument("HOC subdivisions = " + std::to_string(subdivisions) + ": must be 0..3");

	// The 12 vertices (0, +-1, +-phi) and cyclic permutations, on the unit sphere.
	const double phi = (1.0 + std::sqrt(5.0)) / 2.0;
	for (int s1 : {-1, 1})
		for (int s2 : {-1, 1})
		{
			m_vertices.emplace_back(0, s1, s2 * phi);
			m_vertices.emplace_back(s1, s2 * phi, 0);
			m_vertices.emplace_back(s2 * phi, 0, s1);
		}
	for (auto& v : m_vertices) v.normalize();
	// Faces: the vertex triples that are pairwise at the edge length (2 before normalisation).
	const double edge = 2.0 / std::sqrt(1 + phi * phi);
	auto adjacent = [&](int a, int b) { return std::abs((m_vertices[a] - m_vertices[b]).norm() - edge) < 1e-9; };
	std::vector<Face> base;
	for (int a = 0; a < 12; a++)
		for (int b = a + 1; b < 12; b++)
			for (int c = b + 1; c < 12; c++)
				if (adjacent(a, b) && adjacent(b, c) && adjacent(a, c))
				{
					Face f{{a, b, c}};
					if (det3(m_vertices[a], m_vertices[b], m_vertices[c]) < 0) std::swap(f.v[1], f.v[2]);
					base.push_back(f);
				}
	if (base.size() != 20) throw std::logic_error("HocGeometry: icosahedron construction failed");
	for (const auto& f : base)
		m_baseNormals.push_back((m_vertices[f.v[0]] + m_vertices[f.v[1]] + m_vertices[f.v[2]]).normalized());
	m_levels.push_back(base);

	std::map<std::pair<int, int>, int> midpoints;
	auto midpoint = [&](int a, int b) {
		const auto key = std::minmax(a, b);
		auto it = midpoints.find(key);
		if (it != midpoints.end()) return it->second;
		m_vertices.push_back((m_vertices[a] + m_vertices[b]).normalized());
		const int id = static_cast<int>(m_vertices.size()) - 1;
		midpoints.emplace(key, id);
		return id;
	};
	for (int l = 0; l < subdivisions; l++)
	{
		std::vector<Face> next;
		for (const auto& f : m_levels.back())
		{
			const int a = f.v[0], b = f.v[1], c = f.v[2];
			const int ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
			next.push_back({{a, ab, ca}});
			next.push_back({{ab, b, bc}});
			next.push_back({{ca, bc, c}});
			next.push_back({{ab, bc, ca}});
		}
		m_levels.push_back(std::move(next));
	}
	m_faces = m_levels.back();

	// Edge adjacency of the finest level.
	std::map<std::pair<int, int>, std::vector<int>> byEdge;
	for (int i = 0; i < numFaces(); i++)
		for (int e = 0; e < 3; e++) byEdge[std::minmax(m_faces[i].v[e], m_faces[i].v[(e + 1) % 3])].push_back(i);
	m_neighbours.assign(m_faces.size(), {-1, -1, -1});
	for (int i = 0; i < numFaces(); i++)
		for (int e = 0; e < 3; e++)
		{
			const auto& sharing = byEdge.at(std::minmax(m_faces[i].v[e], m_faces[i].v[(e + 1) % 3]));
			for (int j : sharing)
				if (j != i) m_neighbours[i][e] = j;
		}
}

int HocGeometry::face(const Eigen::Vector3d& d) const
{
	int best = 0;
	double bestDot = -2;
	for (int f = 0; f < 20; f++)
	{
		const double dot = m_baseNormals[f].dot(d);
		if (dot > bestDot) bestDot = dot, best = f;
	}
	// Descend: the child whose spherical triangle contains d. Of the four, take the one whose
	// smallest edge determinant is largest (robust on the shared edges).
	for (int l = 1; l <= m_subdivisions; l++)
	{
		int bestChild = 4 * best;
		double bestMin = -1e300;
		for (int c = 4 * best; c < 4 * best + 4; c++)
		{
			const auto& v = m_levels[l][c].v;
			const auto &a = m_vertices[v[0]], &b = m_vertices[v[1]], &cc = m_vertices[v[2]];
			const double m = std::min({det3(a, b, d), det3(b, cc, d), det3(cc, a, d)});
			if (m > bestMin) bestMin = m, bestChild = c;
		}
		best = bestChild;
	}
	return best;
}

int HocGeometry::shell(double dist) const
{
	for (int i = 0; i < numShells(); i++)
		if (dist <= m_radii[i]) return i;
	return numShells() - 1;
}

int HocGeometry::bin(const Eigen::Vector3d& point, const Eigen::Vector3d& cameraCentre) const
{
	const Eigen::Vector3d d = cameraCentre - point;
	const double n = d.norm();
	if (!(n > 0)) return -1;
	return shell(n) * numFaces() + face(d);
}

Eigen::Vector3d HocGeometry::faceCentre(int f) const
{
	const auto v = faceVertices(f);
	return (v[0] + v[1] + v[2]).normalized();
}

std::array<Eigen::Vector3d, 3> HocGeometry::faceVertices(int f) const
{
	const auto& v = m_faces.at(f).v;
	return {m_vertices[v[0]], m_vertices[v[1]], m_vertices[v[2]]};
}

std::array<int, 3> HocGeometry::faceNeighbours(int f) const { return m_neighbours.at(f); }

}  // namespace keygrid::maps
