/** \file FloorFrameEstimator.cpp
 * The run's floor frame: options, the lowest-plane search and the pooled estimator.
 */
#include "detail/OptionValues.h"

#include <keygrid/core/PinholeIntrinsics.h>
#include <keygrid/maps/FloorFrameEstimator.h>
#include <mrpt/math/CQuaternion.h>
#include <mrpt/math/geometry.h>

#include <Eigen/Eigenvalues>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <cstdint>
#include <algorithm>
#include <limits>
#include <optional>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace keygrid::maps
{
using mrpt::math::TPoint3D;
using mrpt::math::TPoint3Df;
using mrpt::math::TVector3D;

// ------------------------------------------------------------------ options
core::OptionFields FloorFrameOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.addCustom(
		"T_world_floor",
		{[this](const std::string& text) { givenPose = text == "estimate" ? "" : text; },
		 [this] { return givenPose.empty() ? std::string("estimate") : givenPose; }},
		"estimate, or the floor frame given as [x y z yaw pitch roll] (m, deg) in the SLAM world");
	f.addCustom(
		"up_hint", detail::vectorValue(upHint), "\"up\" in the SLAM world for the first search; 0 0 0 = mean -y of the keyframe cameras");
	f.add("initial_keyframes", initialKeyframes, "estimate at every keyframe until this many contributed (and the floor is found)", R::atLeast(1));
	f.add("reestimate_every", reestimateEvery, "then re-estimate every N keyframes and after trajectory corrections", R::atLeast(1));
	f.add("reservoir_size", reservoirSize, "depth samples kept (uniform over all keyframes)", R::atLeast(100));
	f.add("pixel_step", pixelStep, "depth samples: every n-th pixel in rows and columns", R::atLeast(1));
	f.add("min_depth", minDepth, "depth range of the samples, lower end [m]", R::atLeast(0));
	f.add("max_depth", maxDepth, "depth range of the samples, upper end [m] (above min_depth)");
	f.add("min_change", minChange, "smaller moves of the floor [m] ...", R::atLeast(0));
	f.add("min_change_deg", minChangeDeg, "... and tilts [deg] keep the previous estimate", R::atLeast(0));
	f.add("inlier_distance", inlierDistance, "point-to-plane distance of a floor inlier [m]", R::positive());
	f.add("hypotheses", hypotheses, "RANSAC hypotheses per round", R::atLeast(1));
	f.add("rounds", rounds, "search rounds; up = the previous round's normal", R::atLeast(1));
	f.add("max_tilt_deg", maxTiltDeg, "largest angle normal / up hint in the first round [deg]", R::between(0, 90));
	f.add("refine_tilt_deg", refineTiltDeg, "the same in later rounds [deg]", R::between(0, 90));
	f.add("lowest_fraction", lowestFraction, "hypotheses from this share of the lowest samples", R::aboveUpTo(0, 1));
	f.add("min_support", minSupport, "least floor support: share of the samples ...", R::aboveUpTo(0, 1));
	f.add("min_support_points", minSupportPoints, "... and least number of samples", R::atLeast(3));
	f.add("below_distance", belowDistance, "a sample this far under a plane is below it [m]", R::positive());
	f.add("max_below_share", maxBelowShare, "more samples below than this x least support: not the floor", R::atLeast(0));
	f.add("parallel_planes", parallelPlanes, "tilt from all large horizontal planes (furniture tops), height from the floor");
	f.add("vertical_planes", verticalPlanes, "with parallel_planes: the normal also perpendicular to large vertical planes (walls)");
	f.add("min_camera_height", minCameraHeight, "cameras (all but 5 %) at least this high above the floor [m]", R::atLeast(0));
	f.add("seed", seed, "random seed (reservoir, RANSAC)");
	return f;
}

void FloorFrameOptions::validate(const std::string& s) const
{
	core::validateFields(*this, s);
	if (!givenPose.empty())
	{
		try
		{
			given();
		}
		catch (const std::exception&)
		{
			throw std::invalid_argument("[" + s + "] T_world_floor = '" + givenPose + "' (expected \"[x y z yaw pitch roll]\" (m, deg))");
		}
	}
	if (!(maxDepth > minDepth))
		throw std::invalid_argument("[" + s + "] max_depth = " + std::to_string(maxDepth) + " (must be > min_depth = " + std::to_string(minDepth) + ")");
}

std::optional<mrpt::poses::CPose3D> FloorFrameOptions::given() const
{
	if (givenPose.empty()) return std::nullopt;
	mrpt::poses::CPose3D p;
	p.fromString(givenPose);
	return p;
}

// ------------------------------------------------------------ plane search
namespace
{
double dot(const TVector3D& a, const TVector3D& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

struct Counts
{
	std::size_t inliers{0}, below{0};
};

Counts count(const std::vector<TPoint3D>& pts, const FloorPlane& pl, double tol, double belowDist)
{
	Counts c;
	for (const auto& p : pts)
	{
		const double h = pl.height(p);
		if (std::abs(h) <= tol) c.inliers++;
		else if (h < -belowDist) c.below++;
	}
	return c;
}

/** The RANSAC's scoring subsample as three coordinate arrays, which countRange reads two
 * points at a time (the hypotheses are thousands per search). */
struct ScorePoints
{
	std::vector<double> x, y, z;
	explicit ScorePoints(const std::vector<TPoint3D>& pts)
	{
		x.reserve(pts.size()), y.reserve(pts.size()), z.reserve(pts.size());
		for (const auto& p : pts) x.push_back(p.x), y.push_back(p.y), z.push_back(p.z);
	}
	std::size_t size() const { return x.size(); }
};

/** count() of the points [begin, end) of s, added to c: the same heights as
 * FloorPlane::height (the same operations in the same order), two points at a time with SSE2
 * (GCC does not vectorise the two conditional counts by itself). */
void countRange(const ScorePoints& s, const FloorPlane& pl, double tol, double belowDist, std::size_t begin, std::size_t end, Counts& c)
{
	const double nx = pl.normal.x, ny = pl.normal.y, nz = pl.normal.z, d = pl.d, low = -belowDist;
	const double* x = s.x.data();
	const double* y = s.y.data();
	const double* z = s.z.data();
	std::size_t i = begin, inliers = 0, below = 0;
#if defined(__SSE2__)
	const __m128d vnx = _mm_set1_pd(nx), vny = _mm_set1_pd(ny), vnz = _mm_set1_pd(nz), vd = _mm_set1_pd(d);
	const __m128d vtol = _mm_set1_pd(tol), vlow = _mm_set1_pd(low), sign = _mm_set1_pd(-0.0);
	__m128i vin = _mm_setzero_si128(), vbelow = _mm_setzero_si128();
	for (; i + 2 <= end; i += 2)
	{
		const __m128d h = _mm_add_pd(
			_mm_add_pd(_mm_add_pd(_mm_mul_pd(vnx, _mm_loadu_pd(x + i)), _mm_mul_pd(vny, _mm_loadu_pd(y + i))), _mm_mul_pd(vnz, _mm_loadu_pd(z + i))),
			vd);
		const __m128d in = _mm_cmple_pd(_mm_andnot_pd(sign, h), vtol);  // all ones where |h| <= tol
		const __m128d under = _mm_andnot_pd(in, _mm_cmplt_pd(h, vlow));
		vin = _mm_sub_epi64(vin, _mm_castpd_si128(in));  // all ones is -1
		vbelow = _mm_sub_epi64(vbelow, _mm_castpd_si128(under));
	}
	std::int64_t lanes[2];
	_mm_storeu_si128(reinterpret_cast<__m128i*>(lanes), vin);
	inliers += static_cast<std::size_t>(lanes[0] + lanes[1]);
	_mm_storeu_si128(reinterpret_cast<__m128i*>(lanes), vbelow);
	below += static_cast<std::size_t>(lanes[0] + lanes[1]);
#endif
	for (; i < end; i++)
	{
		const double h = nx * x[i] + ny * y[i] + nz * z[i] + d;
		const bool in = std::abs(h) <= tol;
		inliers += in;
		below += !in && h < low;
	}
	c.inliers += inliers;
	c.below += below;
}

/** count() on the scoring subsample, for a hypothesis that only matters as a clear plane (at
 * most maxBelow points below) with more than `beat` inliers: nullopt as soon as it cannot be
 * one, checked between blocks of points. */
std::optional<Counts> countToBeat(const ScorePoints& s, const FloorPlane& pl, double tol, double belowDist, double maxBelow, std::size_t beat)
{
	constexpr std::size_t kBlock = 512;
	Counts c;
	const std::size_t n = s.size();
	for (std::size_t start = 0; start < n; start += kBlock)
	{
		const std::size_t end = std::min(n, start + kBlock);
		countRange(s, pl, tol, belowDist, start, end, c);
		if (static_cast<double>(c.below) > maxBelow || c.inliers + (n - end) <= beat) return std::nullopt;
	}
	return c;
}

/** Weighted least-squares plane through the points within `tol` of `pl` (weighted centroid
 * + smallest eigenvector of the weighted scatter), its normal on the side of pl's. */
FloorPlane refine(const std::vector<TPoint3D>& pts, const std::vector<double>& w, const FloorPlane& pl, double tol)
{
	Eigen::Vector3d c = Eigen::Vector3d::Zero();
	Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
	double W = 0;
	std::size_t n = 0;
	for (std::size_t i = 0; i < pts.size(); i++)
	{
		const auto& p = pts[i];
		if (std::abs(pl.height(p)) > tol) continue;
		const double wi = w.empty() ? 1.0 : w[i];
		const Eigen::Vector3d v(p.x, p.y, p.z);
		c += wi * v;
		S += wi * v * v.transpose();
		W += wi;
		n++;
	}
	if (n < 3 || !(W > 0)) return pl;
	c /= W;
	const Eigen::Matrix3d C = S / W - c * c.transpose();
	Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
	Eigen::Vector3d nrm = es.eigenvectors().col(0);
	if (nrm.dot(Eigen::Vector3d(pl.normal.x, pl.normal.y, pl.normal.z)) < 0) nrm = -nrm;
	FloorPlane out;
	out.normal = TVector3D(nrm.x(), nrm.y(), nrm.z());
	out.d = -nrm.dot(c);
	out.inliers = n;
	return out;
}

/** refine() until the plane settles: the inliers are chosen by the previous plane, so with
 * noise as wide as the band a few iterations are needed to shed the hypothesis' tilt. */
FloorPlane refineToConvergence(const std::vector<TPoint3D>& pts, const std::vector<double>& w, FloorPlane pl, double tol)
{
	constexpr int kMaxIterations = 20;
	for (int it = 0; it < kMaxIterations; it++)
	{
		const FloorPlane r = refine(pts, w, pl, tol);
		const double cosAng = r.normal.x * pl.normal.x + r.normal.y * pl.normal.y + r.normal.z * pl.normal.z;
		const bool settled = cosAng > std::cos(1e-4) && std::abs(r.d - pl.d) < 1e-5;
		pl = r;
		if (settled) break;
	}
	return pl;
}

/** A large vertical plane (wall, cabinet front) and the weight of its constraint n . normal = 0
 * on the floor's normal: the weighted sample count times the plane's variance along "up"
 * (how well its points pin the plane's own tilt about a horizontal axis). */
struct VerticalPlane
{
	FloorPlane plane;
	Eigen::Vector3d normal;
	double weight{0};
};

/** Up to kMaxWalls large planes within kWallTiltDeg of vertical, largest first (sequential
 * RANSAC on `score`, refined by weighted least squares on all points): each must hold
 * kWallMinShare of the points and span at least kWallMinSpread (rms) along "up". */
std::vector<VerticalPlane> findVerticalPlanes(
	const std::vector<TPoint3D>& pts, const std::vector<double>& w, std::vector<TPoint3D> score, const TVector3D& up,
	const FloorFrameOptions& o)
{
	constexpr int kMaxWalls = 4, kHypotheses = 400;
	constexpr double kWallTiltDeg = 10.0, kWallMinShare = 0.03, kWallMinSpread = 0.2;
	const double sinTilt = std::sin(kWallTiltDeg * M_PI / 180.0);
	const auto minScore = static_cast<std::size_t>(std::ceil(kWallMinShare * static_cast<double>(score.size())));
	const Eigen::Vector3d u(up.x, up.y, up.z);
	std::mt19937 rng(o.seed + 1);
	std::vector<VerticalPlane> out;
	std::vector<FloorPlane> found;
	for (int wall = 0; wall < kMaxWalls && score.size() >= std::max<std::size_t>(3, minScore); wall++)
	{
		std::uniform_int_distribution<std::size_t> pick(0, score.size() - 1);
		std::optional<FloorPlane> best;
		for (int it = 0; it < kHypotheses; it++)
		{
			const TPoint3D &a = score[pick(rng)], &b = score[pick(rng)], &c = score[pick(rng)];
			TVector3D nrm = mrpt::math::crossProduct3D(b - a, c - a);
			const double nn = nrm.norm();
			if (nn < 1e-12) continue;
			nrm *= 1.0 / nn;
			if (std::abs(dot(nrm, up)) > sinTilt) continue;
			FloorPlane pl;
			pl.normal = nrm;
			pl.d = -dot(nrm, TVector3D(a.x, a.y, a.z));
			pl.inliers = count(score, pl, o.inlierDistance, 1e9).inliers;
			if (pl.inliers >= minScore && (!best || pl.inliers > best->inliers)) best = pl;
		}
		if (!best) break;
		// Refined on all points that no wall found before claims.
		std::vector<TPoint3D> mine;
		std::vector<double> mineW;
		for (std::size_t i = 0; i < pts.size(); i++)
		{
			if (std::abs(best->height(pts[i])) > o.inlierDistance) continue;
			if (std::any_of(found.begin(), found.end(), [&](const FloorPlane& f) { return std::abs(f.height(pts[i])) <= o.inlierDistance; }))
				continue;
			mine.push_back(pts[i]);
			if (!w.empty()) mineW.push_back(w[i]);
		}
		const FloorPlane r = refineToConvergence(mine, mineW, *best, o.inlierDistance);
		found.push_back(r);
		score.erase(std::remove_if(score.begin(), score.end(), [&](const TPoint3D& p) { return std::abs(r.height(p)) <= o.inlierDistance; }),
					score.end());
		if (std::abs(dot(r.normal, up)) > sinTilt) continue;
		Eigen::Vector3d c = Eigen::Vector3d::Zero();
		Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
		double W = 0;
		for (std::size_t i = 0; i < mine.size(); i++)
		{
			if (std::abs(r.height(mine[i])) > o.inlierDistance) continue;
			const double wi = mineW.empty() ? 1.0 : mineW[i];
			const Eigen::Vector3d v(mine[i].x, mine[i].y, mine[i].z);
			c += wi * v;
			M += wi * v * v.transpose();
			W += wi;
		}
		if (!(W > 0)) continue;
		c /= W;
		const double vVar = u.dot((M / W - c * c.transpose()) * u);
		if (vVar < kWallMinSpread * kWallMinSpread) continue;
		out.push_back({r, Eigen::Vector3d(r.normal.x, r.normal.y, r.normal.z), W * vVar});
	}
	return out;
}

/** The floor's normal from every large horizontal plane (floor, table and sofa tops,
 * ceiling), its height from the floor alone.
 *
 * A floor seen only as a strip (at the foot of a wall, beyond a table) leaves its tilt across
 * the strip to a few centimetres of depth noise; the tops of furniture are parallel to it and
 * often far larger. Planes are peaks of the histogram of heights above the current floor
 * (bins of inlierDistance): a band of +-inlierDistance around a local maximum that holds at
 * least `minSupport` points and twice the mean of the bands 3..6 bins away on either side
 * (walls spread evenly over heights), and whose points form a plane (smallest principal
 * direction within refineTiltDeg of the normal, rms thickness below inlierDistance) that
 * extends in two directions (second principal spread above 0.1 m). The common normal n
 * minimises sum_k sum_{i in k} w_i (n . (p_i - c_k))^2 with c_k each plane's weighted
 * centroid: the smallest eigenvector of the summed centred scatters. Membership follows the
 * new normal for a few iterations. */
FloorPlane refineWithParallelPlanes(
	const std::vector<TPoint3D>& pts, const std::vector<double>& w, FloorPlane floor, const FloorFrameOptions& o,
	std::size_t minSupport, const std::vector<VerticalPlane>& walls, std::size_t* planesUsed)
{
	constexpr int kIterations = 3;
	const double bin = o.inlierDistance;
	// A point on a wall is no floor point: the foot of a wall lies on one side of the floor
	// only and would lift a floor seen as a narrow strip.
	std::vector<char> onWall(pts.size(), 0);
	for (std::size_t i = 0; i < pts.size(); i++)
		for (const auto& v : walls)
			if (std::abs(v.plane.height(pts[i])) <= o.inlierDistance) onWall[i] = 1;
	for (int it = 0; it < kIterations; it++)
	{
		double hMax = 0;
		for (const auto& p : pts) hMax = std::max(hMax, floor.height(p));
		const int nBins = static_cast<int>(std::ceil((hMax + 2 * bin) / bin)) + 1;
		if (nBins < 3 || nBins > 100000) return floor;
		// Bin k covers heights [(k - 1) bin - bin / 2, k bin - bin / 2): bin 1 is centred on 0.
		auto binOf = [&](double h) { return static_cast<int>(std::floor(h / bin + 0.5)) + 1; };
		std::vector<std::size_t> hist(static_cast<std::size_t>(nBins), 0);
		for (const auto& p : pts)
		{
			const int k = binOf(floor.height(p));
			if (k >= 0 && k < nBins) hist[static_cast<std::size_t>(k)]++;
		}
		auto at = [&](int k) -> double { return k >= 0 && k < nBins ? static_cast<double>(hist[static_cast<std::size_t>(k)]) : 0.0; };
		std::vector<double> peaks{0.0};  // the floor itself
		for (int k = 4; k < nBins; k++)
		{
			if (at(k) < at(k - 1) || at(k) < at(k + 1)) continue;
			const double band = at(k - 1) + at(k) + at(k + 1);
			double around = 0;
			for (int j = 3; j <= 6; j++) around += at(k - j) + at(k + j);
			if (band >= static_cast<double>(minSupport) && band >= 2.0 * 3.0 * around / 8.0) peaks.push_back((k - 1) * bin);
		}
		Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
		Eigen::Vector3d floorCentroid = Eigen::Vector3d::Zero();
		std::size_t used = 0;
		const Eigen::Vector3d n0(floor.normal.x, floor.normal.y, floor.normal.z);
		for (std::size_t k = 0; k < peaks.size(); k++)
		{
			Eigen::Vector3d c = Eigen::Vector3d::Zero();
			Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
			double W = 0;
			for (std::size_t i = 0; i < pts.size(); i++)
			{
				if (onWall[i] || std::abs(floor.height(pts[i]) - peaks[k]) > o.inlierDistance) continue;
				const double wi = w.empty() ? 1.0 : w[i];
				const Eigen::Vector3d v(pts[i].x, pts[i].y, pts[i].z);
				c += wi * v;
				M += wi * v * v.transpose();
				W += wi;
			}
			if (!(W > 0)) continue;
			c /= W;
			const Eigen::Matrix3d C = M / W - c * c.transpose();
			if (k == 0) floorCentroid = c;
			else
			{
				Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
				const auto ev = es.eigenvalues();
				const bool flat = std::abs(es.eigenvectors().col(0).dot(n0)) >= std::cos(o.refineTiltDeg * M_PI / 180.0) &&
					ev(0) < o.inlierDistance * o.inlierDistance && ev(1) > 0.01;
				if (!flat) continue;
			}
			S += W * C;
			used++;
		}
		if (planesUsed) *planesUsed = used;
		for (const auto& v : walls) S += v.weight * v.normal * v.normal.transpose();
		Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(S);
		Eigen::Vector3d n = es.eigenvectors().col(0);
		if (n.dot(n0) < 0) n = -n;
		floor.normal = TVector3D(n.x(), n.y(), n.z());
		floor.d = -n.dot(floorCentroid);
	}
	return floor;
}

/** True when every camera but 5 % is at least minHeight above the plane. */
bool camerasAbove(const std::vector<TPoint3D>& cams, const FloorPlane& pl, double minHeight)
{
	const std::size_t allowed = cams.size() / 20;
	std::size_t low = 0;
	for (const auto& c : cams)
		if (pl.height(c) < minHeight && ++low > allowed) return false;
	return true;
}
}  // namespace

std::optional<FloorPlaneFit> estimateLowestFloorPlane(
	const std::vector<TPoint3D>& pts, const TVector3D& upIn, const std::vector<TPoint3D>& cams,
	const FloorFrameOptions& o, const std::vector<double>& weights)
{
	if (!weights.empty() && weights.size() != pts.size())
		throw std::invalid_argument("estimateLowestFloorPlane: " + std::to_string(weights.size()) + " weights for " + std::to_string(pts.size()) + " points");
	constexpr std::size_t kScorePoints = 8000;
	const double upNorm = upIn.norm();
	if (!(upNorm > 0)) throw std::invalid_argument("estimateLowestFloorPlane: zero up hint");
	const std::size_t n = pts.size();
	const std::size_t minSupport = std::max<std::size_t>(
		static_cast<std::size_t>(o.minSupportPoints), static_cast<std::size_t>(std::ceil(o.minSupport * n)));
	if (n < minSupport) return std::nullopt;
	const double maxBelow = o.maxBelowShare * static_cast<double>(minSupport);

	// Hypotheses are scored on an even subsample, with the thresholds scaled to its size.
	std::vector<TPoint3D> score;
	const std::size_t stride = (n + kScorePoints - 1) / kScorePoints;
	for (std::size_t i = 0; i < n; i += stride) score.push_back(pts[i]);
	const double scale = static_cast<double>(score.size()) / static_cast<double>(n);
	const double minSupportS = std::max(3.0, std::floor(static_cast<double>(minSupport) * scale));
	const double maxBelowS = maxBelow * scale;
	const ScorePoints scoreSoA(score);

	std::mt19937 rng(o.seed);
	TVector3D up = upIn * (1.0 / upNorm);
	double tiltDeg = o.maxTiltDeg;
	std::optional<FloorPlaneFit> best;
	std::vector<std::pair<double, std::size_t>> byHeight(n);
	std::vector<std::size_t> lowest;
	for (int round = 0; round < o.rounds; round++)
	{
		for (std::size_t i = 0; i < n; i++)
			byHeight[i] = {up.x * pts[i].x + up.y * pts[i].y + up.z * pts[i].z, i};
		const std::size_t nLow = std::max<std::size_t>(3, static_cast<std::size_t>(std::ceil(o.lowestFraction * n)));
		std::nth_element(byHeight.begin(), byHeight.begin() + static_cast<std::ptrdiff_t>(std::min(nLow, n) - 1), byHeight.end());
		lowest.clear();
		for (std::size_t i = 0; i < std::min(nLow, n); i++) lowest.push_back(byHeight[i].second);
		const double cosTilt = std::cos(tiltDeg * M_PI / 180.0);
		std::uniform_int_distribution<std::size_t> pick(0, lowest.size() - 1);

		// Best hypothesis with few points below (clear), and the fallback with the fewest.
		std::optional<FloorPlane> clear, fallback;
		Counts clearC, fallbackC;
		for (int it = 0; it < o.hypotheses; it++)
		{
			const TPoint3D& a = pts[lowest[pick(rng)]];
			const TPoint3D& b = pts[lowest[pick(rng)]];
			const TPoint3D& c = pts[lowest[pick(rng)]];
			TVector3D nrm = mrpt::math::crossProduct3D(b - a, c - a);
			const double nn = nrm.norm();
			if (nn < 1e-12) continue;
			nrm *= 1.0 / nn;
			if (dot(nrm, up) < 0) nrm *= -1.0;
			if (dot(nrm, up) < cosTilt) continue;
			FloorPlane pl;
			pl.normal = nrm;
			pl.d = -dot(nrm, TVector3D(a.x, a.y, a.z));
			if (!camerasAbove(cams, pl, o.minCameraHeight)) continue;
			// Once a clear plane is found the fallback is no longer used: a hypothesis only
			// matters as a clear plane with more inliers, and its count stops once it cannot be.
			if (clear)
			{
				const auto k = countToBeat(scoreSoA, pl, o.inlierDistance, o.belowDistance, maxBelowS, clearC.inliers);
				if (k && static_cast<double>(k->inliers) >= minSupportS) clear = pl, clearC = *k;
				continue;
			}
			Counts k;
			countRange(scoreSoA, pl, o.inlierDistance, o.belowDistance, 0, scoreSoA.size(), k);
			if (static_cast<double>(k.inliers) < minSupportS) continue;
			if (static_cast<double>(k.below) <= maxBelowS)
			{
				if (!clear || k.inliers > clearC.inliers) clear = pl, clearC = k;
			}
			else if (!fallback || k.below < fallbackC.below || (k.below == fallbackC.below && k.inliers > fallbackC.inliers))
				fallback = pl, fallbackC = k;
		}
		const bool isClear = clear.has_value();
		if (!isClear && !fallback) break;
		FloorPlane r = refineToConvergence(pts, weights, isClear ? *clear : *fallback, o.inlierDistance);
		const Counts k = count(pts, r, o.inlierDistance, o.belowDistance);
		if (k.inliers < minSupport || dot(r.normal, up) < cosTilt || !camerasAbove(cams, r, o.minCameraHeight)) break;
		r.inliers = k.inliers;
		FloorPlaneFit fit;
		fit.plane = r;
		fit.below = k.below;
		fit.clearBelow = static_cast<double>(k.below) <= maxBelow;
		// A clear plane is not replaced by a fallback of a later round.
		if (best && best->clearBelow && !fit.clearBelow) break;
		best = fit;
		up = r.normal;
		tiltDeg = o.refineTiltDeg;
	}
	// searchUnderTheWinner: the samples under the plane found (a clear one, as a generous
	// maxBelowShare lets through, or the fallback) may form a large plane of their own (the
	// floor under a desk top): that lower plane is the floor. Scattered stray samples form none.
	if (o.searchUnderTheWinner && best && best->below >= minSupport)
	{
		std::vector<TPoint3D> under;
		std::vector<double> underWeights;
		for (std::size_t i = 0; i < n; i++)
			if (best->plane.height(pts[i]) < -o.belowDistance)
			{
				under.push_back(pts[i]);
				if (!weights.empty()) underWeights.push_back(weights[i]);
			}
		FloorFrameOptions lower = o;
		lower.minSupport = std::numeric_limits<double>::min();  // the absolute count below rules
		lower.minSupportPoints = static_cast<int>(minSupport);
		lower.parallelPlanes = false;
		lower.lowestFraction = 1.0;  // the few points under it: stray ones may be the lowest
		if (const auto f = estimateLowestFloorPlane(under, best->plane.normal, cams, lower, underWeights))
		{
			const Counts k = count(pts, f->plane, o.inlierDistance, o.belowDistance);
			best->plane = f->plane;
			best->plane.inliers = k.inliers;
			best->below = k.below;
			best->clearBelow = static_cast<double>(k.below) <= maxBelow;
		}
	}
	if (best && o.parallelPlanes)
	{
		const auto walls = o.verticalPlanes ? findVerticalPlanes(pts, weights, score, best->plane.normal, o) : std::vector<VerticalPlane>{};
		best->verticalPlanes = walls.size();
		best->plane = refineWithParallelPlanes(pts, weights, best->plane, o, minSupport, walls, &best->parallelPlanes);
		const Counts k = count(pts, best->plane, o.inlierDistance, o.belowDistance);
		best->plane.inliers = k.inliers;
		best->below = k.below;
	}
	return best;
}

// --------------------------------------------------------------- estimator
FloorFrameEstimator::FloorFrameEstimator(const FloorFrameOptions& opts) : m_opts(opts), m_rng(opts.seed)
{
	m_opts.validate();
	if (const auto g = m_opts.given())
	{
		m_given = true;
		m_T_world_floor = *g;
	}
}

std::vector<TPoint3Df> FloorFrameEstimator::depthSamples(
	const float* depth, int rows, int cols, double fx, double fy, double cx, double cy, const FloorFrameOptions& o)
{
	std::vector<TPoint3Df> out;
	const int step = o.pixelStep;
	const core::PinholeIntrinsics K{fx, fy, cx, cy};
	for (int r = step / 2; r < rows; r += step)
		for (int c = step / 2; c < cols; c += step)
		{
			const float z = depth[static_cast<std::size_t>(r) * cols + c];
			if (!(z >= o.minDepth && z <= o.maxDepth)) continue;
			const Eigen::Vector3d p_cam = K.backProject(c, r, z);
			out.emplace_back(static_cast<float>(p_cam.x()), static_cast<float>(p_cam.y()), z);
		}
	return out;
}

bool FloorFrameEstimator::due() const
{
	const auto k = static_cast<int>(m_poses.size());
	if (!m_T_world_floor || k <= m_opts.initialKeyframes) return true;
	return (k - m_opts.initialKeyframes) % m_opts.reestimateEvery == 0;
}

bool FloorFrameEstimator::addKeyframe(
	uint64_t id, const mrpt::poses::CPose3D& T_world_cam, const std::vector<TPoint3Df>& samples, double stamp)
{
	if (m_given) return false;
	const bool known = m_poses.count(id) > 0;
	m_lastStamp = std::max(m_lastStamp, stamp);
	if (m_poses.empty()) m_firstKeyframe = id;
	m_poses[id] = T_world_cam;
	if (known) return false;
	// Reservoir sampling (Vitter's algorithm R): every sample offered so far is kept with the
	// same probability reservoirSize / seen.
	const auto cap = static_cast<std::size_t>(m_opts.reservoirSize);
	for (const auto& p : samples)
	{
		m_seen++;
		if (m_samples.size() < cap)
			m_samples.push_back({id, p});
		else
		{
			std::uniform_int_distribution<std::size_t> slot(0, m_seen - 1);
			const std::size_t j = slot(m_rng);
			if (j < cap) m_samples[j] = {id, p};
		}
	}
	return due() && reestimate();
}

bool FloorFrameEstimator::updatePoses(
	const std::map<uint64_t, mrpt::poses::CPose3D>& newPoses, const std::map<uint64_t, double>& scales)
{
	if (m_given) return false;
	bool any = false;
	for (const auto& [id, T] : newPoses)
		if (auto it = m_poses.find(id); it != m_poses.end())
		{
			it->second = T;
			any = true;
		}
	if (!scales.empty())
		for (auto& smp : m_samples)
			if (const auto it = scales.find(smp.keyframe); it != scales.end())
			{
				const float f = static_cast<float>(it->second);
				smp.p_cam = mrpt::math::TPoint3Df(smp.p_cam.x * f, smp.p_cam.y * f, smp.p_cam.z * f);
			}
	return any && reestimate();
}

bool FloorFrameEstimator::reestimate()
{
	if (m_given || m_poses.empty()) return false;
	const auto t0 = std::chrono::steady_clock::now();
	std::vector<TPoint3D> pts;
	std::vector<double> w;
	pts.reserve(m_samples.size());
	w.reserve(m_samples.size());
	for (const auto& s : m_samples)
	{
		pts.push_back(m_poses.at(s.keyframe).composePoint(TPoint3D(s.p_cam.x, s.p_cam.y, s.p_cam.z)));
		// Depth noise of structured-light and stereo sensors grows as z^2: weight 1 / z^4.
		const double z = std::max(0.5, static_cast<double>(s.p_cam.z));
		w.push_back(1.0 / (z * z * z * z));
	}
	std::vector<TPoint3D> cams;
	TVector3D upSum(0, 0, 0);
	for (const auto& [id, T] : m_poses)
	{
		cams.push_back(T.translation());
		upSum = upSum + T.rotateVector(TVector3D(0, -1, 0));
	}
	const TVector3D up = m_opts.upHint.norm() > 0 ? m_opts.upHint : upSum;
	const auto fit = upSum.norm() > 0 || m_opts.upHint.norm() > 0 ? estimateLowestFloorPlane(pts, up, cams, m_opts, w)
																   : std::nullopt;
	m_estimates++;
	m_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	if (!fit) return false;
	const auto& first = m_poses.at(m_firstKeyframe);
	const TPoint3D cam = first.translation();
	if (m_plane)
	{
		// Keep the previous frame when the new one is (nearly) the same plane.
		const double dh = std::abs(m_plane->height(cam) - fit->plane.height(cam));
		const double dAng = std::acos(std::clamp(dot(m_plane->normal, fit->plane.normal), -1.0, 1.0)) * 180.0 / M_PI;
		if (dh <= m_opts.minChange && dAng <= m_opts.minChangeDeg) return false;
	}
	m_plane = fit->plane;
	m_T_world_floor = floorPoseFromPlane(fit->plane, cam, first.rotateVector(TVector3D(0, 0, 1)));
	Update u;
	u.keyframes = m_poses.size();
	u.stamp = m_lastStamp;
	u.T_world_floor = *m_T_world_floor;
	u.samples = pts.size();
	u.inliers = fit->plane.inliers;
	u.below = fit->below;
	u.clearBelow = fit->clearBelow;
	u.planes = fit->parallelPlanes;
	u.walls = fit->verticalPlanes;
	m_history.push_back(u);
	return true;
}

namespace
{
std::string poseJson(const mrpt::poses::CPose3D& T)
{
	mrpt::math::CQuaternionDouble q;
	T.getAsQuaternion(q);
	char b[256];
	std::snprintf(b, sizeof(b), "[%.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g]", T.x(), T.y(), T.z(), q.x(), q.y(), q.z(), q.r());
	return b;
}
}  // namespace

std::string FloorFrameEstimator::toJson() const
{
	std::ostringstream o;
	o << "{\"source\": \"" << (m_given ? "given" : m_T_world_floor ? "estimated" : "none") << "\"";
	o << ", \"T_world_floor\": " << (m_T_world_floor ? poseJson(*m_T_world_floor) : std::string("null"));
	char b[320];
	std::snprintf(b, sizeof(b), ", \"keyframes\": %zu, \"samples\": %zu, \"estimates\": %zu, \"seconds\": %.4f", m_poses.size(),
				  m_samples.size(), m_estimates, m_seconds);
	o << b << ", \"history\": [";
	for (std::size_t i = 0; i < m_history.size(); i++)
	{
		const auto& u = m_history[i];
		std::snprintf(b, sizeof(b), "%s{\"keyframes\": %zu, \"stamp\": %.6f, \"samples\": %zu, \"inliers\": %zu, \"below\": %zu, \"clear_below\": %s, \"planes\": %zu, \"walls\": %zu, \"T_world_floor\": ",
					  i ? ", " : "", u.keyframes, u.stamp, u.samples, u.inliers, u.below, u.clearBelow ? "true" : "false", u.planes, u.walls);
		o << b << poseJson(u.T_world_floor) << "}";
	}
	o << "]}";
	return o.str();
}

}  // namespace keygrid::maps
