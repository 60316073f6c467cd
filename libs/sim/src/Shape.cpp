#include <keygrid/sim/Shape.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace keygrid::sim
{
ShapeType shapeTypeFromString(const std::string& s)
{
	if (s == "quad") return ShapeType::Quad;
	if (s == "box") return ShapeType::Box;
	if (s == "cylinder") return ShapeType::Cylinder;
	throw std::invalid_argument("type = '" + s + "' is not one of quad, box, cylinder");
}

std::string toString(ShapeType t)
{
	switch (t)
	{
		case ShapeType::Quad:
			return "quad";
		case ShapeType::Box:
			return "box";
		case ShapeType::Cylinder:
			return "cylinder";
	}
	return "?";
}

namespace
{
constexpr double kParallelEps = 1e-12;

bool intersectQuad(
	const Eigen::Vector3d& half, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tMin,
	double tMax, LocalHit& hit)
{
	if (std::abs(d.z()) < kParallelEps) return false;
	const double t = -o.z() / d.z();
	if (!(t > tMin && t < tMax)) return false;
	const double x = o.x() + t * d.x(), y = o.y() + t * d.y();
	if (std::abs(x) > half.x() || std::abs(y) > half.y()) return false;
	hit.t = t;
	hit.face = 0;
	return true;
}

// Slab method (Kay & Kajiya): the ray is inside the box where it is inside all three slabs.
bool intersectBox(
	const Eigen::Vector3d& half, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tMin,
	double tMax, LocalHit& hit)
{
	double tNear = -std::numeric_limits<double>::infinity();
	double tFar = std::numeric_limits<double>::infinity();
	int face = -1;
	for (int i = 0; i < 3; i++)
	{
		if (std::abs(d[i]) < kParallelEps)
		{
			if (std::abs(o[i]) > half[i]) return false;
			continue;
		}
		const double inv = 1.0 / d[i];
		double t1 = (-half[i] - o[i]) * inv, t2 = (half[i] - o[i]) * inv;
		// Entering through the -half side when moving towards +, else through +half.
		int f = 2 * i + (d[i] > 0 ? 0 : 1);
		if (t1 > t2) std::swap(t1, t2);
		if (t1 > tNear)
		{
			tNear = t1;
			face = f;
		}
		tFar = std::min(tFar, t2);
		if (tNear > tFar) return false;
	}
	// Only the entry point counts: a camera inside a solid sees nothing of it.
	if (face < 0 || !(tNear > tMin && tNear < tMax)) return false;
	hit.t = tNear;
	hit.face = face;
	return true;
}

bool intersectCylinder(
	const Eigen::Vector3d& half, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tMin,
	double tMax, LocalHit& hit)
{
	const double r = half.x(), h = half.z();
	bool found = false;
	double best = tMax;
	// Side: |o_xy + t d_xy|^2 = r^2, entry root only.
	const double a = d.x() * d.x() + d.y() * d.y();
	if (a > kParallelEps)
	{
		const double b = 2.0 * (o.x() * d.x() + o.y() * d.y());
		const double c = o.x() * o.x() + o.y() * o.y() - r * r;
		const double disc = b * b - 4.0 * a * c;
		if (disc >= 0)
		{
			const double t = (-b - std::sqrt(disc)) / (2.0 * a);
			if (t > tMin && t < best && std::abs(o.z() + t * d.z()) <= h)
			{
				best = t;
				hit.face = 0;
				found = true;
			}
		}
	}
	// Caps z = +h (face 1) and z = -h (face 2).
	if (std::abs(d.z()) > kParallelEps)
	{
		for (int f = 1; f <= 2; f++)
		{
			const double zc = f == 1 ? h : -h;
			const double t = (zc - o.z()) / d.z();
			if (!(t > tMin && t < best)) continue;
			const double x = o.x() + t * d.x(), y = o.y() + t * d.y();
			if (x * x + y * y > r * r) continue;
			best = t;
			hit.face = f;
			found = true;
		}
	}
	if (found) hit.t = best;
	return found;
}

void sampleRect(
	const Eigen::Vector3d& corner, const Eigen::Vector3d& e1, const Eigen::Vector3d& e2,
	double step, const std::function<void(const Eigen::Vector3d&)>& f)
{
	const int n1 = std::max(1, static_cast<int>(std::ceil(e1.norm() / step)));
	const int n2 = std::max(1, static_cast<int>(std::ceil(e2.norm() / step)));
	for (int i = 0; i <= n1; i++)
		for (int j = 0; j <= n2; j++)
			f(corner + e1 * (static_cast<double>(i) / n1) + e2 * (static_cast<double>(j) / n2));
}
}  // namespace

bool Shape::intersect(
	const Eigen::Vector3d& o, const Eigen::Vector3d& d, double tMin, double tMax,
	LocalHit& hit) const
{
	switch (type)
	{
		case ShapeType::Quad:
			return intersectQuad(half, o, d, tMin, tMax, hit);
		case ShapeType::Box:
			return intersectBox(half, o, d, tMin, tMax, hit);
		case ShapeType::Cylinder:
			return intersectCylinder(half, o, d, tMin, tMax, hit);
	}
	return false;
}

Eigen::Vector3d Shape::normal(const Eigen::Vector3d& p, int face) const
{
	switch (type)
	{
		case ShapeType::Quad:
			return Eigen::Vector3d::UnitZ();
		case ShapeType::Box:
		{
			Eigen::Vector3d n = Eigen::Vector3d::Zero();
			n[face / 2] = (face % 2) ? 1.0 : -1.0;
			return n;
		}
		case ShapeType::Cylinder:
			if (face == 1) return Eigen::Vector3d::UnitZ();
			if (face == 2) return -Eigen::Vector3d::UnitZ();
			return Eigen::Vector3d(p.x(), p.y(), 0).normalized();
	}
	return Eigen::Vector3d::UnitZ();
}

Eigen::Vector2d Shape::surfaceUV(const Eigen::Vector3d& p, int face) const
{
	// Each face gets its own offset into the tile so that faces of one object differ.
	const double off = 0.737 * face;
	switch (type)
	{
		case ShapeType::Quad:
			return {p.x() + half.x(), p.y() + half.y()};
		case ShapeType::Box:
			switch (face / 2)
			{
				case 0:
					return {p.y() + half.y() + off, p.z() + half.z()};
				case 1:
					return {p.x() + half.x() + off, p.z() + half.z()};
				default:
					return {p.x() + half.x() + off, p.y() + half.y()};
			}
		case ShapeType::Cylinder:
			if (face == 0) return {(std::atan2(p.y(), p.x()) + M_PI) * half.x(), p.z() + half.z()};
			return {p.x() + half.x() + off, p.y() + half.y()};
	}
	return {0, 0};
}

std::array<Eigen::Vector3d, 8> Shape::boundingCorners() const
{
	const double hz = type == ShapeType::Quad ? 0.0 : half.z();
	std::array<Eigen::Vector3d, 8> c;
	for (int i = 0; i < 8; i++)
		c[i] = Eigen::Vector3d(
			(i & 1) ? half.x() : -half.x(), (i & 2) ? half.y() : -half.y(), (i & 4) ? hz : -hz);
	return c;
}

void Shape::sampleSurface(double step, const std::function<void(const Eigen::Vector3d&)>& f) const
{
	const Eigen::Vector3d ex = Eigen::Vector3d::UnitX(), ey = Eigen::Vector3d::UnitY(),
						  ez = Eigen::Vector3d::UnitZ();
	const double a = half.x(), b = half.y(), c = half.z();
	switch (type)
	{
		case ShapeType::Quad:
			sampleRect(Eigen::Vector3d(-a, -b, 0), 2 * a * ex, 2 * b * ey, step, f);
			return;
		case ShapeType::Box:
			for (double s : {-1.0, 1.0})
			{
				sampleRect(Eigen::Vector3d(s * a, -b, -c), 2 * b * ey, 2 * c * ez, step, f);
				sampleRect(Eigen::Vector3d(-a, s * b, -c), 2 * a * ex, 2 * c * ez, step, f);
				sampleRect(Eigen::Vector3d(-a, -b, s * c), 2 * a * ex, 2 * b * ey, step, f);
			}
			return;
		case ShapeType::Cylinder:
		{
			const double r = a;
			const int nA = std::max(8, static_cast<int>(std::ceil(2 * M_PI * r / step)));
			const int nZ = std::max(1, static_cast<int>(std::ceil(2 * c / step)));
			for (int i = 0; i < nA; i++)
			{
				const double th = 2 * M_PI * i / nA;
				for (int j = 0; j <= nZ; j++)
					f(Eigen::Vector3d(r * std::cos(th), r * std::sin(th), -c + 2 * c * j / nZ));
			}
			const int nR = std::max(1, static_cast<int>(std::ceil(r / step)));
			for (double z : {-c, c})
				for (int k = 0; k <= nR; k++)
				{
					const double rk = r * k / nR;
					const int n = std::max(1, static_cast<int>(std::ceil(2 * M_PI * rk / step)));
					for (int i = 0; i < n; i++)
					{
						const double th = 2 * M_PI * i / n;
						f(Eigen::Vector3d(rk * std::cos(th), rk * std::sin(th), z));
					}
				}
			return;
		}
	}
}

}  // namespace keygrid::sim
