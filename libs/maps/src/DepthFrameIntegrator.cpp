#include "detail/Grid3DParallel.h"
#include "detail/OptionValues.h"

#include <keygrid/maps/Dda.h>
#include <keygrid/maps/DepthFrameIntegrator.h>
#include <mrpt/config/CConfigFileBase.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <climits>
#include <cstring>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <unordered_map>

namespace keygrid
{
// ---------------------------------------------------------------- options
core::OptionFields DepthIntegrationOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("maxRange", maxRange, "rays are cut at this distance from the camera centre: free space up to it, no hit [m]", R::positive());
	f.add("minRange", minRange, "pixels nearer than this to the camera centre are ignored [m] (< maxRange)", R::atLeast(0));
	f.add("pixelDecimation", pixelDecimation, "use every n-th pixel in rows and columns", R::atLeast(1));
	f.add("threads", threads, "integration worker threads, 0 = all hardware threads (same result for any count)");
	f.add("logOddsHit", logOddsHit, "log-odds added to the voxel a ray ends in", R::positive());
	f.add("logOddsMiss", logOddsMiss, "log-odds added to the voxels a ray crosses before its end", detail::negative());
	f.add("logOddsMin", logOddsMin, "lower clamp of a voxel's log-odds", detail::negative());
	f.add("logOddsMax", logOddsMax, "upper clamp of a voxel's log-odds", R::positive());
	f.add(
		"maxDenseMarkVoxels", maxDenseMarkVoxels,
		"largest dense per-frame mark volume [voxels, 1 byte each] in [512, 1073741824]; larger frames take a slower sparse path");
	f.addCustom(
		"discretizeEndpoints", detail::flagValue(discretizeEndpoints),
		"one free-space ray per distinct end voxel (to its centre) instead of one per pixel, as OctoMap's discretize");
	return f;
}

void DepthIntegrationOptions::validate(const std::string& s) const
{
	core::validateFields(*this, s);
	if (!(minRange < maxRange))
		throw std::invalid_argument(
			"[" + s + "] minRange = " + std::to_string(minRange) + " (must be < maxRange = " + std::to_string(maxRange) + ")");
	if (!(maxDenseMarkVoxels >= 512 && maxDenseMarkVoxels <= 1073741824.0))
		throw std::invalid_argument(
			"[" + s + "] maxDenseMarkVoxels = " + std::to_string(maxDenseMarkVoxels) + " (must be in [512, 1073741824], one byte per voxel)");
}

// ---------------------------------------------------------------- ray table
void PixelRayTable::update(const core::RgbdCamera& cam)
{
	const bool same = m_valid && cam.width == m_cam.width && cam.height == m_cam.height &&
		cam.fx == m_cam.fx && cam.fy == m_cam.fy && cam.cx == m_cam.cx && cam.cy == m_cam.cy &&
		cam.dist == m_cam.dist;
	if (same) return;
	m_cam = cam;
	m_w = cam.width;
	m_h = cam.height;
	m_xy.assign(2 * static_cast<std::size_t>(m_w) * m_h, 0.0f);
	if (!cam.hasDistortion())
	{
		const core::PinholeIntrinsics K = cam.pinhole();
		for (unsigned v = 0; v < m_h; ++v)
			for (unsigned u = 0; u < m_w; ++u)
			{
				float* p = &m_xy[2 * (static_cast<std::size_t>(v) * m_w + u)];
				p[0] = static_cast<float>(K.rayX(u));
				p[1] = static_cast<float>(K.rayY(v));
			}
	}
	else
	{
		cv::Mat K = (cv::Mat_<double>(3, 3) << cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
		cv::Mat D(1, 5, CV_64F);
		for (int i = 0; i < 5; ++i) D.at<double>(i) = cam.dist[i];
		std::vector<cv::Point2f> px, und;
		px.reserve(static_cast<std::size_t>(m_w) * m_h);
		for (unsigned v = 0; v < m_h; ++v)
			for (unsigned u = 0; u < m_w; ++u) px.emplace_back(float(u), float(v));
		cv::undistortPoints(px, und, K, D);
		for (std::size_t i = 0; i < und.size(); ++i)
		{
			m_xy[2 * i] = und[i].x;
			m_xy[2 * i + 1] = und[i].y;
		}
	}
	m_valid = true;
}

namespace
{
/** End voxel and flag (0 skip, 1 cut at maxRange, 2 hit) of n pixels with unit-stride depth
 * `d` [m] and unit-depth rays `xy`, for the pose (R row-major, origin o). The voxel of a cut
 * pixel is left for the caller (returns whether there is any). Branch-free so that the
 * compiler can vectorise it: compiled twice below, for the baseline ISA and for AVX2 (chosen
 * at run time). Both use the same IEEE operations in the same order (no FMA contraction: the
 * AVX2 variant does not enable FMA), so the results are bit-identical to the scalar per-pixel
 * code. no-trapping-math lets GCC if-convert the comparisons; it changes no result (only the
 * guarantee about floating-point exception flags). */
#define KEYGRID_END_VOXELS_OF_ROW_BODY                                                           \
	constexpr float kInfF = std::numeric_limits<float>::infinity();                              \
	int anyCut = 0;                                                                              \
	for (unsigned c = 0; c < n; ++c)                                                             \
	{                                                                                            \
		const float d0 = dsrc[c];                                                                \
		const int valid = (d0 > 0.0f) & (d0 < kInfF); /* 0, negative, NaN, inf: invalid */      \
		const float d = valid ? d0 : 1.0f;                                                       \
		const double x0 = xsrc[2 * c] * d, y0 = xsrc[2 * c + 1] * d, z0 = d;                     \
		const double range2 = x0 * x0 + y0 * y0 + z0 * z0;                                       \
		const int cut = range2 > maxR2;                                                          \
		/* a cut pixel's voxel is redone by the caller: use 0 here (no overflow in the casts) */ \
		const double x = cut ? 0.0 : x0, y = cut ? 0.0 : y0, z = cut ? 0.0 : z0;                 \
		const int keep = valid & (range2 >= minR2);                                              \
		anyCut |= keep & cut;                                                                    \
		bf[c] = keep * (2 - cut);                                                                \
		/* floorToInt() spelled out (not inlined across different target options) */           \
		const double qx = (Rs[0] * x + Rs[1] * y + Rs[2] * z + ox) * inv;                        \
		const double qy = (Rs[3] * x + Rs[4] * y + Rs[5] * z + oy) * inv;                        \
		const double qz = (Rs[6] * x + Rs[7] * y + Rs[8] * z + oz) * inv;                        \
		const int32_t ix = static_cast<int32_t>(qx), iy = static_cast<int32_t>(qy),              \
					  iz = static_cast<int32_t>(qz);                                             \
		bx[c] = ix - static_cast<int32_t>(qx < static_cast<double>(ix));                         \
		by[c] = iy - static_cast<int32_t>(qy < static_cast<double>(iy));                         \
		bz[c] = iz - static_cast<int32_t>(qz < static_cast<double>(iz));                         \
	}                                                                                            \
	return anyCut;

#define KEYGRID_END_VOXELS_OF_ROW_ARGS                                                           \
	const float *__restrict dsrc, const float *__restrict xsrc, unsigned n,                      \
		const double *__restrict Rs, double ox, double oy, double oz, double inv, double minR2,  \
		double maxR2, int32_t *__restrict bx, int32_t *__restrict by, int32_t *__restrict bz,    \
		int32_t *__restrict bf

#if defined(__GNUC__) && !defined(__clang__)
#define KEYGRID_NO_TRAPPING_MATH __attribute__((optimize("no-trapping-math")))
#else
#define KEYGRID_NO_TRAPPING_MATH
#endif

KEYGRID_NO_TRAPPING_MATH int endVoxelsOfRowBase(KEYGRID_END_VOXELS_OF_ROW_ARGS)
{
	KEYGRID_END_VOXELS_OF_ROW_BODY
}
#if defined(__x86_64__) || defined(__i386__)
#define KEYGRID_HAVE_AVX2_VARIANT 1
KEYGRID_NO_TRAPPING_MATH __attribute__((target("avx2"))) int endVoxelsOfRowAvx2(
	KEYGRID_END_VOXELS_OF_ROW_ARGS)
{
	KEYGRID_END_VOXELS_OF_ROW_BODY
}
#endif
#undef KEYGRID_END_VOXELS_OF_ROW_BODY
#undef KEYGRID_END_VOXELS_OF_ROW_ARGS
#undef KEYGRID_NO_TRAPPING_MATH

using EndVoxelsOfRowFn = int (*)(const float*, const float*, unsigned, const double*, double, double,
	double, double, double, double, int32_t*, int32_t*, int32_t*, int32_t*);
EndVoxelsOfRowFn endVoxelsOfRowImpl()
{
#ifdef KEYGRID_HAVE_AVX2_VARIANT
	static const EndVoxelsOfRowFn f = __builtin_cpu_supports("avx2") ? &endVoxelsOfRowAvx2 : &endVoxelsOfRowBase;
	return f;
#else
	return &endVoxelsOfRowBase;
#endif
}
}  // namespace

// ---------------------------------------------------------------- integrator
DepthFrameIntegrator::DepthFrameIntegrator(const DepthIntegrationOptions& opts) : m_opts(opts)
{
	m_opts.validate();
}

FrameVoxelUpdates DepthFrameIntegrator::castFrame(
	const cv::Mat& depth, const core::RgbdCamera& cam, const mrpt::poses::CPose3D& T_world_cam,
	double resolution)
{
	if (depth.type() != CV_32FC1)
		throw std::invalid_argument("castFrame: depth must be CV_32FC1 [m]");
	if (depth.cols != static_cast<int>(cam.width) || depth.rows != static_cast<int>(cam.height))
		throw std::invalid_argument(
			"castFrame: depth is " + std::to_string(depth.cols) + "x" +
			std::to_string(depth.rows) + " but the camera is " + std::to_string(cam.width) + "x" +
			std::to_string(cam.height));
	m_rays.update(cam);

	const unsigned dec = m_opts.pixelDecimation;
	const unsigned nu = (cam.width + dec - 1) / dec, nv = (cam.height + dec - 1) / dec;
	const std::size_t n = static_cast<std::size_t>(nu) * nv;
	const bool disc = m_opts.discretizeEndpoints;
	if (!disc)
	{
		m_flags.resize(n);
		m_ends.resize(n);
	}

	const auto Rm = T_world_cam.getRotationMatrix();
	const double R[3][3] = {{Rm(0, 0), Rm(0, 1), Rm(0, 2)}, {Rm(1, 0), Rm(1, 1), Rm(1, 2)},
		{Rm(2, 0), Rm(2, 1), Rm(2, 2)}};
	const mrpt::math::TPoint3D origin(T_world_cam.x(), T_world_cam.y(), T_world_cam.z());
	const double maxR = m_opts.maxRange, minR2 = m_opts.minRange * m_opts.minRange,
				 maxR2 = maxR * maxR;
	constexpr float kInfF = std::numeric_limits<float>::infinity();
	const double inv = 1.0 / resolution;
	const unsigned threads = detail::resolveThreads(m_opts.threads);
	const VoxelIndex o{floorToInt(origin.x * inv), floorToInt(origin.y * inv), floorToInt(origin.z * inv)};
	std::vector<Extent> ext(threads, Extent{o, o, 0});
	m_runs.resize(threads);
	for (auto& r : m_runs) r.clear();

	// Back-projection, end voxels and their bounding box in one pass over the pixels.
	detail::parallelChunks(nv, threads, [&](std::size_t r0, std::size_t r1, unsigned t) {
		Extent e{o, o, 0};
		std::vector<EndVoxel>& runs = m_runs[t];
		VoxelIndex prev{INT32_MIN, 0, 0};
		uint8_t prevFlag = 0;
		if (disc)
		{
			// Discretized mode, per row: (1) end voxel and flag of every pixel in a branch-free
			// loop the compiler can vectorise (the rare rays beyond maxRange are redone in
			// scalar code), (2) runs of equal end voxels collapsed. Arithmetic and results are
			// those of the per-pixel loop below.
			std::vector<int32_t> bx(nu), by(nu), bz(nu);
			std::vector<int32_t> bf(nu);
			const EndVoxelsOfRowFn endVoxelsOfRow = endVoxelsOfRowImpl();
			std::vector<float> rowD(dec > 1 ? nu : 0), rowXY(dec > 1 ? 2 * nu : 0);
			const double Rs[9] = {R[0][0], R[0][1], R[0][2], R[1][0], R[1][1], R[1][2], R[2][0], R[2][1], R[2][2]};
			const double ox = origin.x, oy = origin.y, oz = origin.z;
			for (std::size_t r = r0; r < r1; ++r)
			{
				const unsigned v = static_cast<unsigned>(r) * dec;
				const float* drow = depth.ptr<float>(static_cast<int>(v));
				const float* xy = m_rays.row(v);
				// Depth and ray of pixel c are drow[c * dec], xy[2 * c * dec]: copied for dec > 1
				// so that the loop below reads unit-stride arrays.
				const float* dsrc = drow;
				const float* xsrc = xy;
				if (dec > 1)
				{
					for (unsigned c = 0; c < nu; ++c)
					{
						rowD[c] = drow[c * dec];
						rowXY[2 * c] = xy[2 * c * dec];
						rowXY[2 * c + 1] = xy[2 * c * dec + 1];
					}
					dsrc = rowD.data();
					xsrc = rowXY.data();
				}
				const int anyCut = endVoxelsOfRow(dsrc, xsrc, nu, Rs, ox, oy, oz, inv, minR2, maxR2,
					bx.data(), by.data(), bz.data(), bf.data());
				if (anyCut)
					for (unsigned c = 0; c < nu; ++c)
					{
						if (bf[c] != 1) continue;
						const unsigned u = c * dec;
						const float d = drow[u];
						double x = xy[2 * u] * d, y = xy[2 * u + 1] * d, z = d;
						const double sc = maxR / std::sqrt(x * x + y * y + z * z);
						x *= sc, y *= sc, z *= sc;
						bx[c] = floorToInt((Rs[0] * x + Rs[1] * y + Rs[2] * z + ox) * inv);
						by[c] = floorToInt((Rs[3] * x + Rs[4] * y + Rs[5] * z + oy) * inv);
						bz[c] = floorToInt((Rs[6] * x + Rs[7] * y + Rs[8] * z + oz) * inv);
					}
				for (unsigned c = 0; c < nu; ++c)
				{
					const uint8_t f = static_cast<uint8_t>(bf[c]);
					if (!f) continue;
					++e.rays;
					const VoxelIndex vx{bx[c], by[c], bz[c]};
					// Runs of pixels ending in the same voxel are recorded once.
					if (vx == prev && f == prevFlag) continue;
					prev = vx;
					prevFlag = f;
					runs.push_back({vx, f == 2});
					e.add(vx);
				}
			}
			ext[t] = e;
			return;
		}
		// Per-pixel mode: every pixel's float end point and flag.
		for (std::size_t r = r0; r < r1; ++r)
		{
			const unsigned v = static_cast<unsigned>(r) * dec;
			const float* drow = depth.ptr<float>(static_cast<int>(v));
			const float* xy = m_rays.row(v);
			for (unsigned c = 0; c < nu; ++c)
			{
				const std::size_t i = r * nu + c;
				m_flags[i] = 0;
				const unsigned u = c * dec;
				const float d = drow[u];
				if (!(d > 0.0f && d < kInfF)) continue;  // 0, negative, NaN and inf are invalid
				double x = xy[2 * u] * d, y = xy[2 * u + 1] * d, z = d;
				const double range2 = x * x + y * y + z * z;  // compare squares: no sqrt per pixel
				if (range2 < minR2) continue;
				uint8_t f = 2;
				if (range2 > maxR2)
				{
					const double s = maxR / std::sqrt(range2);
					x *= s, y *= s, z *= s;
					f = 1;
				}
				++e.rays;
				const double w[3] = {R[0][0] * x + R[0][1] * y + R[0][2] * z + origin.x,
					R[1][0] * x + R[1][1] * y + R[1][2] * z + origin.y,
					R[2][0] * x + R[2][1] * y + R[2][2] * z + origin.z};
				// Per-pixel rays end at the float point: take its voxel from the same value.
				m_flags[i] = f;
				m_ends[i] = mrpt::math::TPoint3Df(float(w[0]), float(w[1]), float(w[2]));
				const VoxelIndex vx{floorToInt(double(m_ends[i].x) * inv), floorToInt(double(m_ends[i].y) * inv),
					floorToInt(double(m_ends[i].z) * inv)};
				e.add(vx);
			}
		}
		ext[t] = e;
	});
	Extent all{o, o, 0};
	for (const auto& e : ext) all.merge(e);
	return castRays(origin, n, all, resolution);
}

FrameVoxelUpdates DepthFrameIntegrator::castPoints(
	const mrpt::math::TPoint3D& o, const std::vector<mrpt::math::TPoint3Df>& pts,
	double resolution)
{
	const bool disc = m_opts.discretizeEndpoints;
	const std::size_t n = pts.size();
	m_flags.assign(n, 0);
	m_ends.resize(n);
	m_runs.assign(1, {});
	const double inv = 1.0 / resolution;
	auto vox = [inv](double x, double y, double z) {
		return VoxelIndex{floorToInt(x * inv), floorToInt(y * inv), floorToInt(z * inv)};
	};
	Extent all{vox(o.x, o.y, o.z), vox(o.x, o.y, o.z), 0};
	for (std::size_t i = 0; i < n; ++i)
	{
		const double dx = pts[i].x - o.x, dy = pts[i].y - o.y, dz = pts[i].z - o.z;
		const double range = std::sqrt(dx * dx + dy * dy + dz * dz);
		if (!std::isfinite(range) || range < m_opts.minRange) continue;
		mrpt::math::TPoint3Df p = pts[i];
		m_flags[i] = 2;
		if (range > m_opts.maxRange)
		{
			const double s = m_opts.maxRange / range;
			p = mrpt::math::TPoint3Df(static_cast<float>(o.x + dx * s),
				static_cast<float>(o.y + dy * s), static_cast<float>(o.z + dz * s));
			m_flags[i] = 1;
		}
		const VoxelIndex v = vox(p.x, p.y, p.z);
		if (disc) m_runs[0].push_back({v, m_flags[i] == 2});
		else m_ends[i] = p;
		all.add(v);
		++all.rays;
	}
	return castRays(o, n, all, resolution);
}

namespace
{
/** Relaxed atomic access to the bytes of the plain scratch buffer (GCC/Clang builtins: the
 * buffer is reused between frames, which std::atomic<uint8_t>[] would not allow cheaply). */
inline uint8_t loadMark(const uint8_t& m) { return __atomic_load_n(&m, __ATOMIC_RELAXED); }
inline uint8_t orMark(uint8_t& m, uint8_t bits)
{
	return __atomic_fetch_or(&m, bits, __ATOMIC_RELAXED);
}

using EndVoxel = DepthFrameIntegrator::EndVoxel;
/** Sorts by (z, y, x), a hit first, and keeps one entry per voxel (hit wins). */
void sortUnique(std::vector<EndVoxel>& e)
{
	std::sort(e.begin(), e.end(), [](const EndVoxel& a, const EndVoxel& b) {
		if (a.v.z != b.v.z) return a.v.z < b.v.z;
		if (a.v.y != b.v.y) return a.v.y < b.v.y;
		if (a.v.x != b.v.x) return a.v.x < b.v.x;
		return a.hit > b.hit;
	});
	e.erase(std::unique(e.begin(), e.end(),
				[](const EndVoxel& a, const EndVoxel& b) { return a.v == b.v; }),
		e.end());
}

/** The free marks of one ray on the dense per-frame mark volume (x fastest, strides 1, sy, sz
 * bytes): every voxel of traverseSegment(a, b) except the last one (the end voxel), which is
 * exactly what castOne() marks through traverseSegment's visitor. Same arithmetic as
 * traverseSegment (Dda.h), hence the same voxel sequence, but the volume offset is stepped
 * incrementally (+-1, +-sy, +-sz) instead of being recomputed from the voxel index per visit.
 * `a_v` is the origin in voxel units, `aOff` its offset in the volume. Returns the number of
 * voxels traverseSegment would visit (steps + 1). */
inline std::size_t markFreeLinear(const double a_v[3], const int32_t aCur[3], std::size_t aOff,
	const mrpt::math::TPoint3D& b, double inv, std::ptrdiff_t sy, std::ptrdiff_t sz, uint8_t* marks)
{
	const double b_v[3] = {b.x * inv, b.y * inv, b.z * inv};
	const std::ptrdiff_t stride[3] = {1, sy, sz};
	std::ptrdiff_t stepOff[3];
	int32_t remaining[3];
	double tMax[3], tDelta[3];
	constexpr double kInf = std::numeric_limits<double>::infinity();
	for (int k = 0; k < 3; ++k)
	{
		const int32_t end = floorToInt(b_v[k]);
		const double d = b_v[k] - a_v[k];
		remaining[k] = std::abs(end - aCur[k]);
		if (remaining[k] == 0 || d == 0.0)
		{
			stepOff[k] = 0;
			remaining[k] = 0;
			tMax[k] = kInf;
			tDelta[k] = kInf;
			continue;
		}
		stepOff[k] = d > 0 ? stride[k] : -stride[k];
		tDelta[k] = std::abs(1.0 / d);
		const double boundary = d > 0 ? aCur[k] + 1.0 : static_cast<double>(aCur[k]);
		tMax[k] = (boundary - a_v[k]) / d;
	}
	double tx = tMax[0], ty = tMax[1], tz = tMax[2];
	int32_t rx = remaining[0], ry = remaining[1], rz = remaining[2];
	const int32_t steps = rx + ry + rz;
	std::size_t off = aOff;
	for (int32_t total = steps; total > 0; --total)
	{
		uint8_t& m = marks[off];
		if (!(loadMark(m) & FrameVoxelUpdates::kFree)) orMark(m, FrameVoxelUpdates::kFree);
		// Same comparisons (and tie-breaking) as traverseSegment.
		if (tx < ty)
		{
			if (tx < tz)
			{
				off += stepOff[0];
				tx = --rx > 0 ? tx + tDelta[0] : kInf;
			}
			else
			{
				off += stepOff[2];
				tz = --rz > 0 ? tz + tDelta[2] : kInf;
			}
		}
		else if (ty < tz)
		{
			off += stepOff[1];
			ty = --ry > 0 ? ty + tDelta[1] : kInf;
		}
		else
		{
			off += stepOff[2];
			tz = --rz > 0 ? tz + tDelta[2] : kInf;
		}
	}
	return static_cast<std::size_t>(steps) + 1;
}
}  // namespace

FrameVoxelUpdates DepthFrameIntegrator::castRays(
	const mrpt::math::TPoint3D& origin, std::size_t n, const Extent& extent, double resolution)
{
	if (!(resolution > 0)) throw std::invalid_argument("castRays: resolution must be > 0");
	FrameVoxelUpdates out;
	out.resolution = resolution;
	out.rays = extent.rays;
	if (out.rays == 0) return out;
	const double inv = 1.0 / resolution;
	auto vox = [inv](double x, double y, double z) {
		return VoxelIndex{floorToInt(x * inv), floorToInt(y * inv), floorToInt(z * inv)};
	};
	auto centre = [resolution](const VoxelIndex& v) {
		return mrpt::math::TPoint3D(
			(v.x + 0.5) * resolution, (v.y + 0.5) * resolution, (v.z + 0.5) * resolution);
	};
	const unsigned threads = detail::resolveThreads(m_opts.threads);
	const std::vector<mrpt::math::TPoint3Df>& ends = m_ends;
	const std::vector<uint8_t>& flags = m_flags;
	const VoxelIndex lo = extent.lo, hi = extent.hi;

	const VoxelIndex blo = VoxelBlockGrid::blockOf(lo), bhi = VoxelBlockGrid::blockOf(hi);
	const std::size_t nbx = std::size_t(bhi.x - blo.x + 1), nby = std::size_t(bhi.y - blo.y + 1),
					  nbz = std::size_t(bhi.z - blo.z + 1);
	const double denseVoxels = double(nbx) * double(nby) * double(nbz) * VoxelBlock::kVoxels;
	std::vector<std::size_t> visits(threads, 0);

	// One ray: free marks strictly before the end voxel, a hit mark on it when it is a hit.
	auto castOne = [&](const mrpt::math::TPoint3D& end, const VoxelIndex& endVox, bool hit,
					   auto&& mark) -> std::size_t {
		const std::size_t nvis = traverseSegment(origin, end, resolution, [&](const VoxelIndex& v) {
			if (v == endVox) return false;
			mark(v, FrameVoxelUpdates::kFree);
			return true;
		});
		if (hit) mark(endVox, FrameVoxelUpdates::kHit);
		return nvis;
	};
	auto endOf = [&](std::size_t i) {
		return mrpt::math::TPoint3D(ends[i].x, ends[i].y, ends[i].z);
	};
	constexpr uint8_t kEndHit = 4, kEndCut = 8;  // scratch bits of the discretized mode

	if (denseVoxels <= m_opts.maxDenseMarkVoxels)
	{
		// Dense mark volume (reused scratch) over the block-aligned bounding box, x fastest, so
		// that a DDA step moves the offset by a constant (markFreeLinear).
		const std::size_t nTotal = static_cast<std::size_t>(denseVoxels);
		if (m_marks.size() < nTotal) m_marks.resize(nTotal);
		std::fill(m_marks.begin(), m_marks.begin() + static_cast<std::ptrdiff_t>(nTotal), uint8_t(0));
		uint8_t* marks = m_marks.data();
		const VoxelIndex vlo = VoxelBlockGrid::firstVoxelOf(blo);
		const std::size_t nx = nbx * VoxelBlock::kSide, ny = nby * VoxelBlock::kSide;
		auto offsetOf = [&](const VoxelIndex& v) {
			return std::size_t(v.x - vlo.x) + nx * (std::size_t(v.y - vlo.y) + ny * std::size_t(v.z - vlo.z));
		};
		auto slot = [&](const VoxelIndex& v) -> uint8_t& { return marks[offsetOf(v)]; };
		const double a_v[3] = {origin.x * inv, origin.y * inv, origin.z * inv};
		const int32_t aCur[3] = {floorToInt(a_v[0]), floorToInt(a_v[1]), floorToInt(a_v[2])};
		const std::size_t aOff = offsetOf(VoxelIndex{aCur[0], aCur[1], aCur[2]});
		const std::ptrdiff_t sy = std::ptrdiff_t(nx), sz = std::ptrdiff_t(nx * ny);
		// One ray on the dense volume: free marks before the end voxel, a hit mark on it.
		auto castDense = [&](const mrpt::math::TPoint3D& end, const VoxelIndex& endVox, bool hit) {
			const std::size_t nvis = markFreeLinear(a_v, aCur, aOff, end, inv, sy, sz, marks);
			if (hit) orMark(slot(endVox), FrameVoxelUpdates::kHit);
			return nvis;
		};
		if (m_opts.discretizeEndpoints)
		{
			// Pass 1: the thread that first flags an end voxel records it (the runs already
			// dropped repeats of the previous pixel's end voxel).
			std::vector<std::vector<EndVoxel>> found(m_runs.size());
			detail::parallelChunks(m_runs.size(), threads, [&](std::size_t b, std::size_t e, unsigned) {
				for (std::size_t t = b; t < e; ++t)
					for (const EndVoxel& ev : m_runs[t])
					{
						const uint8_t bit = ev.hit ? kEndHit : kEndCut;
						uint8_t& a = slot(ev.v);
						if (loadMark(a) & bit) continue;
						if (!(orMark(a, bit) & bit)) found[t].push_back(ev);
					}
			});
				std::vector<EndVoxel> uniq;
			for (auto& f : found) uniq.insert(uniq.end(), f.begin(), f.end());
			sortUnique(uniq);
			out.castRays = uniq.size();
				// Pass 2: one ray per distinct end voxel, to its centre.
			detail::parallelChunks(uniq.size(), threads, [&](std::size_t b, std::size_t e, unsigned t) {
				std::size_t vis = 0;
				for (std::size_t i = b; i < e; ++i)
					vis += castDense(centre(uniq[i].v), uniq[i].v, uniq[i].hit);
				visits[t] = vis;
			}, 2000);
		}
		else
		{
			out.castRays = out.rays;
			detail::parallelChunks(n, threads, [&](std::size_t b, std::size_t e, unsigned t) {
				std::size_t vis = 0;
				for (std::size_t i = b; i < e; ++i)
					if (flags[i])
						vis += castDense(endOf(i), vox(ends[i].x, ends[i].y, ends[i].z), flags[i] == 2);
				visits[t] = vis;
			});
		}
		// Blocks with any free / hit mark become chunks (the scratch bits 4 and 8 are dropped):
		// a block's 512 marks are 64 rows of 8 bytes in the volume.
		constexpr uint64_t kMask = 0x0303030303030303ull;
		for (std::size_t bz = 0; bz < nbz; ++bz)
			for (std::size_t by = 0; by < nby; ++by)
				for (std::size_t bx = 0; bx < nbx; ++bx)
				{
					const uint8_t* base = marks + bx * VoxelBlock::kSide +
						nx * (by * VoxelBlock::kSide + ny * bz * VoxelBlock::kSide);
					bool any = false;
					for (int r = 0; r < VoxelBlock::kSide * VoxelBlock::kSide && !any; ++r)
					{
						uint64_t w;
						std::memcpy(&w, base + (r % VoxelBlock::kSide) * nx + (r / VoxelBlock::kSide) * nx * ny, 8);
						any = (w & kMask) != 0;
					}
					if (!any) continue;
					out.chunks.emplace_back();
					FrameVoxelUpdates::Chunk& ch = out.chunks.back();
					ch.block = {blo.x + int32_t(bx), blo.y + int32_t(by), blo.z + int32_t(bz)};
					for (int lz = 0; lz < VoxelBlock::kSide; ++lz)
						for (int ly = 0; ly < VoxelBlock::kSide; ++ly)
						{
							const uint8_t* row = base + ly * nx + lz * nx * ny;
							uint8_t* dst = &ch.marks[VoxelBlock::linear(0, ly, lz)];
							for (int lx = 0; lx < VoxelBlock::kSide; ++lx) dst[lx] = row[lx] & 3;
						}
				}
	}
	else
	{
		// Sparse path: one thread, a hash map of chunks, sorted afterwards like the dense order.
		out.sparsePath = true;
		std::unordered_map<VoxelIndex, std::size_t, VoxelIndexHash> where;
		auto markSparse = [&](const VoxelIndex& v, uint8_t m) {
			const VoxelIndex b = VoxelBlockGrid::blockOf(v);
			auto it = where.find(b);
			if (it == where.end())
			{
				it = where.emplace(b, out.chunks.size()).first;
				out.chunks.emplace_back();
				out.chunks.back().block = b;
			}
			out.chunks[it->second].marks[VoxelBlockGrid::localLinear(v)] |= m;
		};
		std::size_t vis = 0;
		if (m_opts.discretizeEndpoints)
		{
			std::vector<EndVoxel> uniq;
			for (const auto& r : m_runs) uniq.insert(uniq.end(), r.begin(), r.end());
			sortUnique(uniq);
			out.castRays = uniq.size();
			for (const auto& u : uniq) vis += castOne(centre(u.v), u.v, u.hit, markSparse);
		}
		else
		{
			out.castRays = out.rays;
			for (std::size_t i = 0; i < n; ++i)
				if (flags[i])
					vis += castOne(endOf(i), vox(ends[i].x, ends[i].y, ends[i].z), flags[i] == 2, markSparse);
		}
		visits[0] = vis;
		std::sort(out.chunks.begin(), out.chunks.end(), [](const auto& a, const auto& b) {
			if (a.block.z != b.block.z) return a.block.z < b.block.z;
			if (a.block.y != b.block.y) return a.block.y < b.block.y;
			return a.block.x < b.block.x;
		});
	}
	for (std::size_t v : visits) out.voxelVisits += v;
	for (const auto& ch : out.chunks)
		for (uint8_t m : ch.marks)
		{
			if (FrameVoxelUpdates::isHit(m)) ++out.hitVoxels;
			else if (m) ++out.freeVoxels;
		}
	return out;
}

void DepthFrameIntegrator::apply(
	VoxelBlockGrid& grid, const FrameVoxelUpdates& upd, double travelled) const
{
	if (grid.resolution() != upd.resolution)
		throw std::invalid_argument(
			"apply: grid resolution " + std::to_string(grid.resolution()) +
			" m != update resolution " + std::to_string(upd.resolution) + " m");
	std::vector<VoxelBlock*> blocks(upd.chunks.size());
	for (std::size_t i = 0; i < upd.chunks.size(); ++i)
		blocks[i] = &grid.blockAt(upd.chunks[i].block);

	const float hitL = m_opts.logOddsHit, missL = m_opts.logOddsMiss;
	const float lo = m_opts.logOddsMin, hi = m_opts.logOddsMax;
	const float stamp = static_cast<float>(std::max(0.0, travelled));
	detail::parallelChunks(
		upd.chunks.size(), detail::resolveThreads(m_opts.threads),
		[&](std::size_t b, std::size_t e, unsigned) {
			for (std::size_t i = b; i < e; ++i)
			{
				const auto& marks = upd.chunks[i].marks;
				VoxelBlock& blk = *blocks[i];
				for (int k = 0; k < VoxelBlock::kVoxels; ++k)
				{
					const uint8_t m = marks[k];
					if (!m) continue;
					Voxel& vx = blk.voxels[k];
					const float delta = FrameVoxelUpdates::isHit(m) ? hitL : missL;
					vx.logOdds = std::min(hi, std::max(lo, vx.logOdds + delta));
					vx.travelled = stamp;
				}
			}
		},
		512);
}

}  // namespace keygrid
