/** \file CISMOccupancyGrid2D_insert.cpp
 * Inserting keyframes (sparse points or dense depth) with the practical ISM, floor estimation,
 * rebuild after loop closure, and the observation likelihood.
 */
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <keygrid/maps/FloorToInt.h>
#include <keygrid/maps/GridRayTraversal.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

using namespace keygrid;
using mrpt::math::TPoint3D;
using mrpt::math::TPoint3Df;
using mrpt::poses::CPose3D;

namespace
{
/** The scan camera's pinhole model in float, like the points the inner loops make. */
core::BasicPinholeIntrinsics<float> floatPinhole(const mrpt::obs::CObservation3DRangeScan& obs)
{
	return core::RgbdCamera::FromTCamera(obs.cameraParams, obs.rangeUnits).pinhole().cast<float>();
}

/** Rotation + translation of T_floor_cam as plain floats for the inner loops. */
struct RigidF
{
	float R[9];
	float t[3];
	explicit RigidF(const CPose3D& T)
	{
		const auto& M = T.getRotationMatrix();
		for (int i = 0; i < 3; i++)
			for (int j = 0; j < 3; j++) R[3 * i + j] = static_cast<float>(M(i, j));
		t[0] = static_cast<float>(T.x());
		t[1] = static_cast<float>(T.y());
		t[2] = static_cast<float>(T.z());
	}
	void apply(float x, float y, float z, float& ox, float& oy, float& oz) const
	{
		ox = R[0] * x + R[1] * y + R[2] * z + t[0];
		oy = R[3] * x + R[4] * y + R[5] * z + t[1];
		oz = R[6] * x + R[7] * y + R[8] * z + t[2];
	}
};

/** Combines two updates of one cell from the same keyframe: occupied evidence wins (as in
 * OctoMap), otherwise the most confident free update; the result does not depend on the order of
 * the updates. Each cell thus changes once per keyframe, whatever the number of rays crossing it. */
inline float combine(float cur, float inc)
{
	if (cur > 0.0f || inc > 0.0f) return std::max(cur, inc);
	return std::min(cur, inc);
}
}  // namespace

std::vector<TPoint3Df> keygrid::depthToCameraPoints(
	const mrpt::obs::CObservation3DRangeScan& obs, int decimation)
{
	std::vector<TPoint3Df> out;
	if (!obs.hasRangeImage) return out;
	const int rows = static_cast<int>(obs.rangeImage.rows());
	const int cols = static_cast<int>(obs.rangeImage.cols());
	const auto K = floatPinhole(obs);
	const float units = obs.rangeUnits;
	out.reserve(static_cast<size_t>(rows / decimation + 1) * static_cast<size_t>(cols / decimation + 1));
	for (int r = 0; r < rows; r += decimation)
	{
		const float yn = K.rayY(static_cast<float>(r));
		for (int c = 0; c < cols; c += decimation)
		{
			const uint16_t raw = obs.rangeImage(r, c);
			if (raw == 0) continue;
			const float xn = K.rayX(static_cast<float>(c));
			float z = raw * units;
			if (!obs.range_is_depth) z /= std::sqrt(1.0f + xn * xn + yn * yn);
			out.emplace_back(xn * z, yn * z, z);
		}
	}
	return out;
}

void CISMOccupancyGrid2D::integrateRays(const CPose3D& T_world_cam, const std::vector<TPoint3Df>& pts)
{
	const TInsertionOptions& o = insertionOptions;
	const bool band = heightBand();
	if (band && (m_bandSlices != bandSlicesWanted() || m_band.size() != m_logOdds.size() * static_cast<size_t>(m_bandSlices + 1)))
		resetBand();
	const maps::IsmShape shape = o.ismShape(m_resolution);
	const double l0 = maps::logit(o.pPrior);
	const float lFree = static_cast<float>(maps::logit(o.pFree) - l0);
	const CPose3D T_floor_cam = T_world_cam - floorPose();  // a - b = inv(b) (+) a
	const RigidF T(T_floor_cam);
	const float sx = T.t[0], sy = T.t[1], sz = T.t[2];
	const double halfL = 0.5 * shape.bandWidth;
	const float maxRange2 = static_cast<float>(o.maxRange * o.maxRange);
	const float hMin = static_cast<float>(o.obstacleMinHeight), hMax = static_cast<float>(o.obstacleMaxHeight);
	const float fTol = static_cast<float>(o.floorTolerance);
	const float margin = static_cast<float>(o.floorRayMargin);
	const float sliceH = static_cast<float>(o.bandSliceHeight);
	auto sliceOf = [&](float z) { return std::clamp(floorToInt((z - hMin) / sliceH), 0, m_bandSlices - 1); };

	// 1) classify and collect the rays in the floor frame, with their bounding box.
	struct Ray
	{
		float ex, ey, ez;  // endpoint (floor frame) [m]
		float range;  // horizontal camera -> endpoint distance [m]
		float sigma;  // range noise [m]
		bool obstacle;
		uint64_t slices;  // heightBand: band slices with obstacle points in the endpoint cell
		int cell;  // heightBand: endpoint cell (for grouping), -1 outside the grid
	};
	std::vector<Ray> rays;
	rays.reserve(pts.size());
	double bx0 = sx, bx1 = sx, by0 = sy, by1 = sy;
	for (const auto& p : pts)
	{
		float fx, fy, fz;
		T.apply(p.x, p.y, p.z, fx, fy, fz);
		const bool obstacle = fz >= hMin && fz <= hMax;
		const bool floor = std::abs(fz) <= fTol;
		if (!obstacle && !floor) continue;
		const float dx = fx - sx, dy = fy - sy;
		const float d2 = dx * dx + dy * dy;
		if (!(d2 <= maxRange2) || d2 < 1e-12f) continue;  // also drops NaN points
		Ray r;
		r.range = std::sqrt(d2);
		// A floor ray ends floorRayMargin short of its point, on the same 3D line.
		const float k = obstacle ? 1.0f : (r.range - margin) / r.range;
		if (!(k > 0.0f)) continue;
		r.ex = sx + dx * k;
		r.ey = sy + dy * k;
		r.ez = sz + (fz - sz) * k;
		r.range *= k;
		// Depth along the optical axis drives the noise; the ray is (nearly) horizontal.
		r.sigma = static_cast<float>(maps::rangeSigma(o.rangeNoise, o.sigmaConstant, p.z));
		r.obstacle = obstacle;
		r.slices = 0;
		r.cell = -1;
		// Obstacle rays continue behind the endpoint while the ISM differs from the prior.
		const double reach = obstacle ? r.range + halfL + 8.0 * r.sigma : r.range;
		const double ux = sx + dx / r.range * reach, uy = sy + dy / r.range * reach;
		bx0 = std::min(bx0, ux);
		bx1 = std::max(bx1, ux);
		by0 = std::min(by0, uy);
		by1 = std::max(by1, uy);
		rays.push_back(r);
	}
	if (rays.empty()) return;
	growToContain(bx0 - m_resolution, bx1 + m_resolution, by0 - m_resolution, by1 + m_resolution);

	if (band)
	{
		// One obstacle ray per endpoint cell, to its nearest point; the cell's other points only
		// add their height slices to the occupied end of that ray (their free parts would mostly
		// repeat it, at a multiple of the cost).
		for (Ray& r : rays)
		{
			r.cell = inside(x2idx(r.ex), y2idx(r.ey)) ? x2idx(r.ex) + y2idx(r.ey) * m_sizeX : -1;
			if (r.obstacle) r.slices = uint64_t{1} << sliceOf(r.ez);
		}
		// Only the obstacle rays are grouped: a cell's combined increment does not depend on
		// the order of the rays (see combine()).
		const auto obstaclesEnd = std::partition(rays.begin(), rays.end(), [](const Ray& r) { return r.obstacle; });
		std::sort(rays.begin(), obstaclesEnd, [](const Ray& a, const Ray& b) {
			if (a.cell != b.cell) return a.cell < b.cell;
			return a.range < b.range;
		});
		const size_t obstacles = static_cast<size_t>(obstaclesEnd - rays.begin());
		size_t keep = 0;
		for (size_t i = 0; i < rays.size(); i++)
		{
			if (i < obstacles && keep > 0 && rays[keep - 1].cell == rays[i].cell && rays[i].cell >= 0)
			{
				rays[keep - 1].slices |= rays[i].slices;
				continue;
			}
			rays[keep++] = rays[i];
		}
		rays.resize(keep);
	}

	// 2) trace: every visited cell (heightBand: every visited slice) gets one combined increment.
	const double res = m_resolution;
	auto toCellX = [&](double x) { return (x - m_xMin) / res - 0.5; };  // cell centre at integer
	auto toCellY = [&](double y) { return (y - m_yMin) / res - 0.5; };
	const double csx = toCellX(sx), csy = toCellY(sy);
	auto touch = [&](int cx, int cy, float inc) {
		if (!inside(cx, cy) || inc == 0.0f) return;
		const size_t idx = static_cast<size_t>(cx) + static_cast<size_t>(cy) * m_sizeX;
		float& s = m_scratch[idx];
		if (s == 0.0f)
		{
			m_touched.push_back(static_cast<int>(idx));
			s = inc;
		}
		else
			s = combine(s, inc);
	};
	const size_t stride = static_cast<size_t>(m_bandSlices + 1);
	/* heightBand: the slice updates are summed in a scratch window over the cells this
	 * keyframe's rays can reach (their bounding box and the one-cell reach of the traversals),
	 * not over the whole grid. */
	const BandWindow win = band ? bandWindow(bx0, bx1, by0, by1) : BandWindow{};
	if (band && m_bandScratch.size() < win.cells() * stride) m_bandScratch.assign(win.cells() * stride, 0.0f);
	auto windowBase = [&](int cx, int cy) {
		if (!win.contains(cx, cy)) throw std::logic_error("CISMOccupancyGrid2D: a ray left its scratch window");
		return win.index(cx, cy) * stride;
	};
	auto touchSlot = [&](size_t idx, float inc) {
		float& s = m_bandScratch[idx];
		if (s == 0.0f)
		{
			m_bandTouched.push_back(idx);
			s = inc;
		}
		else
			s = combine(s, inc);
	};
	/* heightBand: the ray crosses the column of a cell between heights za and zb. A free
	 * increment goes to the slices of [za, zb] in the band and, when the ray is below
	 * obstacleMinHeight there, to the cell's ground clearance; an occupied increment to those
	 * slices and to the slices of the ray's endpoint cell (`extra`). */
	auto touchBand = [&](int cx, int cy, float za, float zb, float inc, uint64_t extra) {
		if (!inside(cx, cy) || inc == 0.0f) return;
		if (za > zb) std::swap(za, zb);
		const size_t base = windowBase(cx, cy);
		if (inc < 0.0f && za < hMin && zb >= -fTol) touchSlot(base, inc);
		if (zb >= hMin && za <= hMax)
		{
			const int k1 = sliceOf(zb);
			for (int k = sliceOf(za); k <= k1; k++) touchSlot(base + 1 + static_cast<size_t>(k), inc);
		}
		if (inc > 0.0f)
			for (uint64_t m = extra; m; m &= m - 1) touchSlot(base + 1 + static_cast<size_t>(__builtin_ctzll(m)), inc);
	};
	/* touchBand() for the exact-free increment lFree, which most visits get: it only marks the
	 * column's slots in a bit mask, and each marked slot gets lFree once after the tracing
	 * (combine() does not depend on the order), however many rays crossed the column. */
	if (band && m_freeColumns.size() != m_logOdds.size()) m_freeColumns.assign(m_logOdds.size(), FreeColumn{});
	auto markFree = [&](int cx, int cy, float za, float zb) {
		if (!inside(cx, cy)) return;
		if (za > zb) std::swap(za, zb);
		const size_t cell = static_cast<size_t>(cx) + static_cast<size_t>(cy) * m_sizeX;
		FreeColumn& c = m_freeColumns[cell];
		const FreeColumn before = c;
		if (za < hMin && zb >= -fTol) c.clearance = true;
		if (zb >= hMin && za <= hMax)
		{
			const int k0 = sliceOf(za), k1 = sliceOf(zb);
			const uint64_t upToK1 = k1 >= 63 ? ~uint64_t{0} : (uint64_t{1} << (k1 + 1)) - 1;
			c.slices |= upToK1 & ~((uint64_t{1} << k0) - 1);
		}
		if (before.slices == 0 && !before.clearance && (c.slices != 0 || c.clearance)) m_freeTouched.push_back(cell);
	};
	// Log-odds increment of the practical ISM at distance r; exact-free / prior far from the band.
	auto ismIncrement = [&](double r, const Ray& ray) -> float {
		if (!ray.obstacle) return r <= ray.range ? lFree : 0.0f;
		const double cut = 8.0 * ray.sigma;
		if (r < ray.range - halfL - cut) return lFree;
		if (r > ray.range + halfL + cut) return 0.0f;
		return static_cast<float>(maps::logit(maps::practicalIsm(r, ray.range, ray.sigma, shape)) - l0);
	};

	for (const Ray& ray : rays)
	{
		const double reach = ray.obstacle ? ray.range + halfL + 8.0 * ray.sigma : ray.range;
		const double k = reach / ray.range;
		const double ex = sx + (ray.ex - sx) * k, ey = sy + (ray.ey - sy) * k;
		// heightBand: height of the ray at horizontal distance r, and the half length of the
		// ray's chord through one cell column (one step of the major axis).
		const double slope = (ray.ez - sz) / ray.range;
		const double ux = std::abs(ray.ex - sx) / ray.range, uy = std::abs(ray.ey - sy) / ray.range;
		const double halfChord = 0.5 * res / std::max(ux, uy);
		const double rEnd = ray.obstacle ? reach : ray.range;
		auto visit = [&](int cx, int cy, double r, float inc) {
			if (!band)
			{
				touch(cx, cy, inc);
				return;
			}
			const double ra = std::max(0.0, r - halfChord), rb = std::min(rEnd, r + halfChord);
			const float za = static_cast<float>(sz + slope * ra), zb = static_cast<float>(sz + slope * rb);
			if (inc == lFree)
				markFree(cx, cy, za, zb);
			else
				touchBand(cx, cy, za, zb, inc, ray.slices);
		};
		if (o.rayTraversal == RayTraversal::Bresenham)
		{
			const int c0x = static_cast<int>(std::lround(csx)), c0y = static_cast<int>(std::lround(csy));
			const int c1x = static_cast<int>(std::lround(toCellX(ex)));
			const int c1y = static_cast<int>(std::lround(toCellY(ey)));
			maps::bresenhamLine(c0x, c0y, c1x, c1y, [&](int cx, int cy) {
				const double dx = idx2x(cx) - sx, dy = idx2y(cy) - sy;
				const double r = std::sqrt(dx * dx + dy * dy);
				visit(cx, cy, r, ismIncrement(r, ray));
			});
		}
		else
		{
			maps::wuLine(csx, csy, toCellX(ex), toCellY(ey), [&](int cx, int cy, float w, double px, double py) {
				const double r = res * std::sqrt((px - csx) * (px - csx) + (py - csy) * (py - csy));
				visit(cx, cy, r, w * ismIncrement(r, ray));
			});
		}
	}

	// 3) apply l_t = l_{t-1} + ISM - l0 once per touched cell (heightBand: slice), clamped.
	const float lo = static_cast<float>(o.logOddsMin - l0), hi = static_cast<float>(o.logOddsMax - l0);
	if (band)
	{
		for (size_t cell : m_freeTouched)
		{
			FreeColumn& c = m_freeColumns[cell];
			const size_t base = windowBase(static_cast<int>(cell % static_cast<size_t>(m_sizeX)), static_cast<int>(cell / static_cast<size_t>(m_sizeX)));
			if (c.clearance) touchSlot(base, lFree);
			for (uint64_t m = c.slices; m; m &= m - 1) touchSlot(base + 1 + static_cast<size_t>(__builtin_ctzll(m)), lFree);
			c = FreeColumn{};
		}
		m_freeTouched.clear();
		for (size_t w : m_bandTouched)
		{
			const size_t cell = win.gridCell(w / stride, static_cast<size_t>(m_sizeX));
			const size_t idx = cell * stride + w % stride;
			m_band[idx] = std::clamp(m_band[idx] + m_bandScratch[w], lo, hi);
			m_bandScratch[w] = 0.0f;
			if (m_scratch[cell] == 0.0f)
			{
				m_scratch[cell] = 1.0f;  // marks the cell for the column update below
				m_touched.push_back(static_cast<int>(cell));
			}
		}
		m_bandTouched.clear();
		for (int idx : m_touched)
		{
			m_logOdds[static_cast<size_t>(idx)] = columnLogOdds(static_cast<size_t>(idx));
			m_scratch[static_cast<size_t>(idx)] = 0.0f;
		}
		m_touched.clear();
		return;
	}
	for (int idx : m_touched)
	{
		float& l = m_logOdds[static_cast<size_t>(idx)];
		l = std::clamp(l + m_scratch[static_cast<size_t>(idx)], lo, hi);
		m_scratch[static_cast<size_t>(idx)] = 0.0f;
	}
	m_touched.clear();
}

bool CISMOccupancyGrid2D::insertKeyframePoints(
	uint64_t keyframeId, const CPose3D& T_world_cam, const std::vector<TPoint3D>& points_world)
{
	KeyframeRays kf;
	kf.T_world_cam = T_world_cam;
	kf.points_cam = maps::toCameraFrame(T_world_cam, points_world);
	m_keyframes[keyframeId] = kf;
	if (!floorKnown()) return false;
	integrateRays(kf.T_world_cam, m_keyframes[keyframeId].points_cam);
	return true;
}

std::vector<TPoint3Df> CISMOccupancyGrid2D::reduceDepth(
	const CPose3D& T_world_cam, const mrpt::obs::CObservation3DRangeScan& obs) const
{
	const TInsertionOptions& o = insertionOptions;
	std::vector<TPoint3Df> out;
	if (!obs.hasRangeImage) return out;
	const RigidF T(T_world_cam - floorPose());
	// A local accumulator of endpoint cells centred on the camera footprint, +- maxRange.
	const int half = static_cast<int>(std::ceil(o.maxRange / m_resolution)) + 1;
	const int n = 2 * half + 1;
	const float inv = static_cast<float>(1.0 / m_resolution);
	const float ox = T.t[0] - static_cast<float>(half * m_resolution);
	const float oy = T.t[1] - static_cast<float>(half * m_resolution);
	struct Acc
	{
		int obstacles{0};
		float bestRange{std::numeric_limits<float>::max()};
		TPoint3Df obstacle;
		bool hasFloor{false};
		TPoint3Df floor;
		uint64_t slicesSeen{0}, slicesKept{0};  // heightBand: slices with 1 / enough points
	};
	std::vector<Acc> acc(static_cast<size_t>(n) * n);
	// heightBand: one point for each further height slice of a cell (it marks that slice
	// occupied at the end of the cell's ray), with its accumulator index.
	const bool band = heightBand();
	const int slices = bandSlicesWanted();
	const float sliceH = static_cast<float>(o.bandSliceHeight);
	std::vector<std::pair<size_t, TPoint3Df>> slicePoints;

	const int rows = static_cast<int>(obs.rangeImage.rows());
	const int cols = static_cast<int>(obs.rangeImage.cols());
	const auto K = floatPinhole(obs);
	const float units = obs.rangeUnits;
	const float hMin = static_cast<float>(o.obstacleMinHeight), hMax = static_cast<float>(o.obstacleMaxHeight);
	const float fTol = static_cast<float>(o.floorTolerance);
	const float maxR2 = static_cast<float>(o.maxRange * o.maxRange);
	std::vector<float> xn(static_cast<size_t>(cols));
	for (int c = 0; c < cols; c++) xn[static_cast<size_t>(c)] = K.rayX(static_cast<float>(c));
	const int dec = o.depthDecimation;
	for (int r = 0; r < rows; r += dec)
	{
		const float yn = K.rayY(static_cast<float>(r));
		for (int c = 0; c < cols; c += dec)
		{
			const uint16_t raw = obs.rangeImage(r, c);
			if (raw == 0) continue;
			float z = raw * units;
			const float x = xn[static_cast<size_t>(c)];
			if (!obs.range_is_depth) z /= std::sqrt(1.0f + x * x + yn * yn);
			const float pcx = x * z, pcy = yn * z;
			float px, py, pz;
			T.apply(pcx, pcy, z, px, py, pz);
			const bool obstacle = pz >= hMin && pz <= hMax;
			const bool floor = pz >= -fTol && pz <= fTol;
			if (!obstacle && !floor) continue;
			const float dx = px - T.t[0], dy = py - T.t[1];
			const float d2 = dx * dx + dy * dy;
			if (!(d2 <= maxR2)) continue;
			const int ix = static_cast<int>((px - ox) * inv), iy = static_cast<int>((py - oy) * inv);
			if (ix < 0 || iy < 0 || ix >= n || iy >= n) continue;
			const size_t ai = static_cast<size_t>(ix) + static_cast<size_t>(iy) * n;
			Acc& a = acc[ai];
			if (obstacle)
			{
				a.obstacles++;
				if (band)
				{
					const uint64_t bit = uint64_t{1} << std::clamp(static_cast<int>((pz - hMin) / sliceH), 0, slices - 1);
					const bool enough = o.minPointsPerCell <= 1 || (a.slicesSeen & bit);
					a.slicesSeen |= bit;
					if (enough && !(a.slicesKept & bit))
					{
						a.slicesKept |= bit;
						slicePoints.emplace_back(ai, TPoint3Df(pcx, pcy, z));
					}
				}
				if (d2 < a.bestRange)
				{
					a.bestRange = d2;
					a.obstacle = TPoint3Df(pcx, pcy, z);
				}
			}
			else if (!a.hasFloor)
			{
				a.hasFloor = true;
				a.floor = TPoint3Df(pcx, pcy, z);
			}
		}
	}
	// Kept with the keyframe until the map ends: allocated at its exact size.
	const auto kept = [&](const Acc& a) { return a.obstacles >= o.minPointsPerCell; };
	size_t count = 0;
	for (const Acc& a : acc) count += (kept(a) ? 1u : 0u) + (a.hasFloor ? 1u : 0u);
	for (const auto& sp : slicePoints) count += kept(acc[sp.first]) ? 1u : 0u;
	out.reserve(count);
	for (const Acc& a : acc)
	{
		if (kept(a)) out.push_back(a.obstacle);
		if (a.hasFloor) out.push_back(a.floor);
	}
	for (const auto& [ai, p] : slicePoints)
		if (kept(acc[ai])) out.push_back(p);
	return out;
}

bool CISMOccupancyGrid2D::ensureFloorFromDepth(
	const CPose3D& T_world_cam, const mrpt::obs::CObservation3DRangeScan& obs)
{
	if (floorKnown()) return true;
	if (m_floorExternal) return false;  // waits for setExternalFloorPose()
	const auto pts_cam = depthToCameraPoints(obs, 4);
	std::vector<TPoint3D> pts_world;
	pts_world.reserve(pts_cam.size());
	for (const auto& p : pts_cam) pts_world.push_back(T_world_cam.composePoint(TPoint3D(p.x, p.y, p.z)));
	return estimateFloorFromPoints(pts_world, T_world_cam);
}

bool CISMOccupancyGrid2D::estimateFloorFromPoints(
	const std::vector<TPoint3D>& points_world, const CPose3D& T_world_cam,
	const std::optional<mrpt::math::TVector3D>& upHint)
{
	const auto& hint = insertionOptions.floorUpHint;
	const auto up = hint.norm() > 0 ? hint
					: upHint && upHint->norm() > 0
						? *upHint
						: T_world_cam.rotateVector(mrpt::math::TVector3D(0, -1, 0));
	const auto fwd = T_world_cam.rotateVector(mrpt::math::TVector3D(0, 0, 1));
	const auto cam = T_world_cam.translation();
	const auto plane = maps::estimateFloorPlane(points_world, up, cam, insertionOptions.floorRansac);
	if (!plane) return false;
	m_T_world_floorEstimate = maps::floorPoseFromPlane(*plane, cam, fwd);
	m_floorEstimated = true;
	return true;
}

void CISMOccupancyGrid2D::expectExternalFloorPose()
{
	if (m_floorExternal) return;
	m_floorExternal = true;
	m_floorEstimated = false;
}

void CISMOccupancyGrid2D::setExternalFloorPose(const CPose3D& T_world_floor)
{
	m_floorExternal = true;
	m_floorEstimated = true;
	m_T_world_floorEstimate = T_world_floor;
}

bool CISMOccupancyGrid2D::insertKeyframeDepth(
	uint64_t keyframeId, const CPose3D& T_world_cam, const mrpt::obs::CObservation3DRangeScan& obs)
{
	if (!obs.hasRangeImage) return false;
	if (!ensureFloorFromDepth(T_world_cam, obs)) return false;
	KeyframeRays kf;
	kf.T_world_cam = T_world_cam;
	kf.points_cam = reduceDepth(T_world_cam, obs);
	integrateRays(kf.T_world_cam, kf.points_cam);
	m_keyframes[keyframeId] = std::move(kf);
	return true;
}

bool CISMOccupancyGrid2D::insertDepthScan(const mrpt::obs::CObservation3DRangeScan& scan, const CPose3D& T_world_cam)
{
	scan.load();  // external range images
	return insertKeyframeDepth(m_nextAutoKeyframeId++, T_world_cam, scan);
}

CISMOccupancyGrid2D::BandWindow CISMOccupancyGrid2D::bandWindow(double x0, double x1, double y0, double y1) const
{
	// A traversal visits the cells along its segment and one neighbour across it (anti-aliased
	// lines); its end cells are rounded from cell coordinates: two cells of margin cover both.
	constexpr int kMargin = 2;
	const int cx0 = std::max(0, x2idx(x0) - kMargin), cx1 = std::min(m_sizeX - 1, x2idx(x1) + kMargin);
	const int cy0 = std::max(0, y2idx(y0) - kMargin), cy1 = std::min(m_sizeY - 1, y2idx(y1) + kMargin);
	return BandWindow{cx0, cy0, cx1 - cx0 + 1, cy1 - cy0 + 1};
}

double CISMOccupancyGrid2D::applyTrajectoryCorrection(const std::map<uint64_t, CPose3D>& newPoses)
{
	const auto t0 = std::chrono::steady_clock::now();
	for (const auto& [id, pose] : newPoses)
	{
		auto it = m_keyframes.find(id);
		if (it == m_keyframes.end())
			throw std::out_of_range(
				"applyTrajectoryCorrection: keyframe " + std::to_string(id) + " is not in the map");
		it->second.T_world_cam = pose;
	}
	std::fill(m_logOdds.begin(), m_logOdds.end(), 0.0f);
	std::fill(m_band.begin(), m_band.end(), 0.0f);
	for (const auto& [id, kf] : m_keyframes) integrateRays(kf.T_world_cam, kf.points_cam);
	m_lastRebuildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	return m_lastRebuildSeconds;
}

/* Likelihood of a depth image: the obstacle-band points, each independently, hit an occupied
 * cell with probability p(cell), mixed with an outlier floor:
 *     log L = sum_i log(eps + (1 - eps) p(cell_i)),   eps = outlierProbability. */
double CISMOccupancyGrid2D::depthScanLikelihood(const mrpt::obs::CObservation3DRangeScan& scan, const CPose3D& T_world_cam) const
{
	if (!scan.hasRangeImage) return 0.0;
	scan.load();
	const RigidF T(T_world_cam - floorPose());
	const double eps = likelihoodOptions.outlierProbability;
	double logLik = 0;
	for (const auto& p : depthToCameraPoints(scan, likelihoodOptions.decimation))
	{
		float fx, fy, fz;
		T.apply(p.x, p.y, p.z, fx, fy, fz);
		if (fz < insertionOptions.obstacleMinHeight || fz > insertionOptions.obstacleMaxHeight) continue;
		logLik += std::log(eps + (1.0 - eps) * occupancy(x2idx(fx), y2idx(fy)));
	}
	return logLik;
}
