#include <keygrid/maps/FloorPlaneEstimator.h>
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/math/geometry.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace keygrid::maps
{
core::OptionFields FloorPlaneRansacOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("floorRansac_inlierDistance", inlierDistance, "floor RANSAC: point-to-plane distance of an inlier [m]", R::positive());
	f.add("floorRansac_iterations", iterations, "floor RANSAC: least hypotheses per plane (more when floorRansac_minInlierFraction needs them)", R::atLeast(1));
	f.add("floorRansac_maxTiltDeg", maxTiltDeg, "floor RANSAC: largest angle between the plane normal and the up hint [deg]", R::between(0, 90));
	f.add("floorRansac_minInlierFraction", minInlierFraction, "floor RANSAC: least share of all points on a plane for it to count", R::aboveUpTo(0, 1));
	f.add("floorRansac_minCameraHeight", minCameraHeight, "floor RANSAC: the camera is at least this high above the floor [m]", R::atLeast(0));
	f.add("floorRansac_seed", seed, "floor RANSAC: random seed of the sampling (the same seed gives the same floor)");
	return f;
}

void FloorPlaneRansacOptions::validate(const std::string& s) const { core::validateFields(*this, s); }

namespace
{
using mrpt::math::TPoint3D;
using mrpt::math::TVector3D;

size_t countInliers(const std::vector<TPoint3D>& pts, const FloorPlane& pl, double tol)
{
	size_t n = 0;
	for (const auto& p : pts)
		if (std::abs(pl.height(p)) <= tol) n++;
	return n;
}

/** Least-squares plane through the inliers of `pl`: centroid + smallest eigenvector. */
FloorPlane refine(const std::vector<TPoint3D>& pts, const FloorPlane& pl, double tol)
{
	Eigen::Vector3d c = Eigen::Vector3d::Zero();
	size_t n = 0;
	for (const auto& p : pts)
		if (std::abs(pl.height(p)) <= tol)
		{
			c += Eigen::Vector3d(p.x, p.y, p.z);
			n++;
		}
	if (n < 3) return pl;
	c /= static_cast<double>(n);
	Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
	for (const auto& p : pts)
		if (std::abs(pl.height(p)) <= tol)
		{
			const Eigen::Vector3d d = Eigen::Vector3d(p.x, p.y, p.z) - c;
			C += d * d.transpose();
		}
	Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
	Eigen::Vector3d nrm = es.eigenvectors().col(0);  // smallest eigenvalue first
	if (nrm.dot(Eigen::Vector3d(pl.normal.x, pl.normal.y, pl.normal.z)) < 0) nrm = -nrm;
	FloorPlane out;
	out.normal = TVector3D(nrm.x(), nrm.y(), nrm.z());
	out.d = -nrm.dot(c);
	out.inliers = countInliers(pts, out, tol);
	return out;
}
}  // namespace

/* Sequential RANSAC: extract up to kMaxPlanes dominant planes that are near-perpendicular to
 * the up hint and below the camera (each the max-inlier hypothesis among the points left by the
 * previous ones, refined by least squares), then return the lowest. Taking the max-inlier plane
 * first keeps thin "strips" (a tilted plane cutting the floor along a line) from winning.
 *
 * Number of hypotheses: a plane holding a share f of the points is hit by an all-inlier sample
 * with probability f^3, so finding it with probability P needs N = log(1 - P) / log(1 - f^3)
 * samples (f = 0.1: 4600; f = 0.03: 170 000). The floor of a room seen over several keyframes
 * can hold a few per cent of the points only, so N follows the smallest plane that counts
 * (minInlierFraction of the points left), at least `iterations` and at most kMaxSamples.
 * Samples are cheap: the tilt test rejects most of them before any counting, and hypotheses are
 * scored on an even subsample of at most kScorePoints points; the winner is refined on all. */
std::optional<FloorPlane> estimateFloorPlane(
	const std::vector<TPoint3D>& pts, const TVector3D& upIn, const TPoint3D& cam,
	const FloorPlaneRansacOptions& o)
{
	constexpr int kMaxPlanes = 4;
	constexpr double kSuccessProbability = 0.99;
	constexpr double kMaxSamples = 200000;
	constexpr size_t kScorePoints = 4000;
	o.validate();
	if (pts.size() < 3) return std::nullopt;
	const double upNorm = upIn.norm();
	if (!(upNorm > 0)) throw std::invalid_argument("estimateFloorPlane: zero up hint");
	const TVector3D up = upIn * (1.0 / upNorm);
	const double cosMaxTilt = std::cos(o.maxTiltDeg * M_PI / 180.0);
	const size_t minInliers =
		std::max<size_t>(3, static_cast<size_t>(std::ceil(o.minInlierFraction * pts.size())));
	auto qualifies = [&](const FloorPlane& pl) {
		return pl.normal.x * up.x + pl.normal.y * up.y + pl.normal.z * up.z >= cosMaxTilt &&
			pl.height(cam) >= o.minCameraHeight;
	};

	std::mt19937 rng(o.seed);
	std::vector<TPoint3D> left = pts;
	std::optional<FloorPlane> lowest;
	for (int plane = 0; plane < kMaxPlanes && left.size() >= minInliers; plane++)
	{
		const double f = static_cast<double>(minInliers) / static_cast<double>(left.size());
		const double need = std::log(1 - kSuccessProbability) / std::log1p(-f * f * f);
		const int samples =
			static_cast<int>(std::max<double>(o.iterations, std::min(kMaxSamples, std::ceil(need))));
		// Even subsample for scoring; its threshold is minInliers scaled to its size.
		std::vector<TPoint3D> score;
		const size_t stride = (left.size() + kScorePoints - 1) / kScorePoints;
		for (size_t i = 0; i < left.size(); i += stride) score.push_back(left[i]);
		const double minScore =
			std::floor(static_cast<double>(minInliers) * score.size() / left.size());
		std::uniform_int_distribution<size_t> pick(0, left.size() - 1);
		std::optional<FloorPlane> best;
		for (int it = 0; it < samples; it++)
		{
			const TPoint3D& a = left[pick(rng)];
			const TPoint3D& b = left[pick(rng)];
			const TPoint3D& c = left[pick(rng)];
			TVector3D n = mrpt::math::crossProduct3D(b - a, c - a);
			const double nn = n.norm();
			if (nn < 1e-9) continue;
			n *= 1.0 / nn;
			if (n.x * up.x + n.y * up.y + n.z * up.z < 0) n *= -1.0;
			FloorPlane pl;
			pl.normal = n;
			pl.d = -(n.x * a.x + n.y * a.y + n.z * a.z);
			if (!qualifies(pl)) continue;
			pl.inliers = countInliers(score, pl, o.inlierDistance);
			if (static_cast<double>(pl.inliers) >= minScore && (!best || pl.inliers > best->inliers))
				best = pl;
		}
		if (!best) break;
		FloorPlane r = refine(left, *best, o.inlierDistance);
		r = refine(left, r, o.inlierDistance);
		if (r.inliers < minInliers || !qualifies(r)) break;
		if (!lowest || r.height(cam) > lowest->height(cam)) lowest = r;
		// Remove this plane's inliers and look for the next one.
		left.erase(
			std::remove_if(left.begin(), left.end(), [&](const TPoint3D& p) { return std::abs(r.height(p)) <= o.inlierDistance; }),
			left.end());
	}
	if (lowest) lowest->inliers = countInliers(pts, *lowest, o.inlierDistance);
	return lowest;
}

mrpt::poses::CPose3D floorPoseFromPlane(
	const FloorPlane& pl, const TPoint3D& cam, const TVector3D& forward)
{
	const TVector3D z = pl.normal * (1.0 / pl.normal.norm());
	TVector3D x = forward - z * (forward.x * z.x + forward.y * z.y + forward.z * z.z);
	if (x.norm() < 1e-6)
	{
		// forward is parallel to the normal: take any perpendicular axis.
		x = std::abs(z.x) < 0.9 ? TVector3D(1, 0, 0) : TVector3D(0, 1, 0);
		x = x - z * (x.x * z.x + x.y * z.y + x.z * z.z);
	}
	x *= 1.0 / x.norm();
	const TVector3D y = mrpt::math::crossProduct3D(z, x);
	mrpt::math::CMatrixDouble33 R;
	for (int i = 0; i < 3; i++)
	{
		R(i, 0) = x[i];
		R(i, 1) = y[i];
		R(i, 2) = z[i];
	}
	const double h = pl.height(cam);
	const TPoint3D o(cam.x - h * z.x, cam.y - h * z.y, cam.z - h * z.z);
	mrpt::math::CVectorFixedDouble<3> t;
	t[0] = o.x;
	t[1] = o.y;
	t[2] = o.z;
	return mrpt::poses::CPose3D::FromRotationAndTranslation(R, t);
}

}  // namespace keygrid::maps
