/** \file GridMorphingBlocks.cpp
 * Step 2 of grid morphing (GridMorphing.h): per corrected 8^3 block, the keyframes whose cone
 * meets it and whose lookups can read known voxels in their travel window, then per voxel the
 * weighted average of the earlier log-odds over those keyframes.
 */
#include "detail/Grid3DParallel.h"
#include "detail/GridMorphingDetail.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <vector>

namespace keygrid::detail::morphing
{
namespace
{
/** An affine test c + a . (lx, ly, lz) >= b over the local voxel indices of a block, with the
 * inverse steps and the largest increase of each term over [0, 7]. */
struct AffineTest
{
	double c{0}, a[3]{}, inv[3]{}, max[3]{}, b{0};
	AffineTest() = default;
	AffineTest(double c_, double ax, double ay, double az, double b_) : c(c_), a{ax, ay, az}, b(b_)
	{
		for (int i = 0; i < 3; ++i)
		{
			inv[i] = a[i] != 0 ? 1.0 / a[i] : 0.0;
			max[i] = std::max(0.0, a[i] * (VoxelBlock::kSide - 1));
		}
	}
};

/** Narrows [lo, hi] to the l where v0 + l * step >= b can hold: kept is every l where it holds
 * within 1e-9 (and 1e-6 of l), far more than the rounding of any evaluation of the same test, so
 * only l where it fails are left out. inv = 1 / step (0 when step = 0). */
inline void keepAtLeast(double v0, double step, double inv, double b, double& lo, double& hi)
{
	const double t = (b - 1e-9 - v0) * inv;
	if (step > 0) lo = std::max(lo, t - 1e-6);
	else if (step < 0) hi = std::min(hi, t + 1e-6);
	else if (v0 < b - 1e-9) hi = -1;
}

/** Where the box [lo, hi] (world, axis-aligned) lies relative to the corrected view cone:
 * `Inside` when every point of it is inside by more than 1e-9 m (far more than the rounding of
 * the per-voxel tests, so they cannot fail there), `Outside` when all of it is behind one face by
 * more than 1e-9 m or farther than the range from the camera centre; both from the box centre
 * and half extents (the extreme of a linear function over a box). */
enum class ConeOverlap
{
	Outside,
	Partial,
	Inside
};
ConeOverlap boxVsCone(const PreparedKeyframe& k, const mrpt::math::TPoint3D& lo,
	const mrpt::math::TPoint3D& hi, double maxRange2)
{
	// Squared distances from the camera centre to the nearest and the farthest box point.
	const double c[3] = {k.centreNew.x, k.centreNew.y, k.centreNew.z};
	const double l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
	double near2 = 0, far2 = 0;
	for (int a = 0; a < 3; ++a)
	{
		const double dn = std::max({l[a] - c[a], 0.0, c[a] - h[a]});
		const double df = std::max(std::abs(l[a] - c[a]), std::abs(h[a] - c[a]));
		near2 += dn * dn, far2 += df * df;
	}
	if (near2 > maxRange2) return ConeOverlap::Outside;
	bool inside = far2 <= maxRange2;
	const double d[3] = {0.5 * (l[0] + h[0]) - c[0], 0.5 * (l[1] + h[1]) - c[1], 0.5 * (l[2] + h[2]) - c[2]};
	const double e[3] = {0.5 * (h[0] - l[0]), 0.5 * (h[1] - l[1]), 0.5 * (h[2] - l[2])};
	for (const auto& n : k.face)
	{
		const double mid = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
		const double ext = std::abs(n[0]) * e[0] + std::abs(n[1]) * e[1] + std::abs(n[2]) * e[2];
		if (mid + ext < -1e-9) return ConeOverlap::Outside;
		inside = inside && mid - ext > 1e-9;
	}
	return inside ? ConeOverlap::Inside : ConeOverlap::Partial;
}
}  // namespace

void averageOverCones(const std::vector<std::pair<VoxelIndex, VoxelBlock*>>& outBlocks,
	const std::vector<PreparedKeyframe>& kfs, const std::vector<SourceIndex>& travelSets,
	const MorphingOptions& opts, double res, MorphingStats& st)
{
	const unsigned nt = detail::resolveThreads(opts.threads);
	std::vector<MorphingStats> partial(nt);
	const double zMin = opts.minWeightDistance, pw = opts.weightExponent, invRes = 1.0 / res;
	const double blockEdge = res * VoxelBlock::kSide;
	// Voxel centre [m], as VoxelBlockGrid::centreOf.
	auto centreOf = [res](const VoxelIndex& v) {
		return mrpt::math::TPoint3D((v.x + 0.5) * res, (v.y + 0.5) * res, (v.z + 0.5) * res);
	};
	const double maxRange2 = opts.viewConeMaxRange * opts.viewConeMaxRange;
	const bool trilinear = opts.interpolation == MorphingOptions::Interpolation::Trilinear;
	constexpr int kN = VoxelBlock::kVoxels, kS = VoxelBlock::kSide;
	// w = max(z, zMin)^-p from z^2; p = 2 (default) without pow / sqrt.
	auto weightAt = [&](double z2) {
		return pw == 2.0 ? 1.0 / std::max(z2, zMin * zMin) : std::pow(std::max(std::sqrt(z2), zMin), -pw);
	};
	detail::parallelChunks(outBlocks.size(), nt, [&](std::size_t b0, std::size_t b1, unsigned t) {
		// Counted locally and stored once at the end: the per-thread entries of `partial` share
		// cache lines, and incrementing them in the voxel loop would make the threads contend.
		MorphingStats ps;
		struct Near
		{
			const PreparedKeyframe* k;
			bool partial;  //!< the block straddles the cone: per-voxel cone test needed
			double score;  //!< ranking score (with a keyframe limit)
			VoxelIndex lo, hi;  //!< bounding box of the source voxels lookups through k can use
		};
		std::vector<Near> near;
		// Per-voxel accumulators of one block: sum w, sum w L, best weight and its travel.
		std::vector<double> sw(kN), swl(kN), bestW(kN);
		std::vector<float> bestTravel(kN);
		// Source blocks read through the current keyframe k, direct-mapped by the parity of the
		// block coordinates: the (up to 8) blocks of one trilinear lookup never collide. Each
		// slot keeps bit masks of the block's known voxels in the travel window of k (with the
		// 1e-6 m slack of readableRegion, so a superset); block = nullptr when there are none, as
		// then no voxel of the block can count.
		struct Slot
		{
			VoxelIndex key;
			const VoxelBlock* block;
			/** Known voxels in the window (word z, bit x + 8 y), and the same dilated: near[0] bit
			 * (x, y, z) set when one of (x..x+1, y..y+1, z..z+1) is (meaningful for x, y, z < 7);
			 * near[1 + a] the same without dilating along axis a (for cubes that cross the block
			 * boundary along a). */
			uint64_t in[kS], near[4][kS];
		};
		Slot cache[8];
		const SourceIndex* cacheInfo = nullptr;
		double cacheWlo = 0, cacheWhi = 0;
		auto sourceSlot = [&](const VoxelIndex& b) -> const Slot& {
			Slot& sl = cache[(b.x & 1) | ((b.y & 1) << 1) | ((b.z & 1) << 2)];
			if (sl.key != b)
			{
				sl.key = b;
				sl.block = nullptr;
				if (const SourceBlockInfo* info = cacheInfo->find(b))
				{
					const TravelHistogram& h = info->travels;
					const auto [i, j] = opts.travelWindow > 0 ? h.range(cacheWlo, cacheWhi)
															  : std::make_pair(std::size_t(0), h.travel.size());
					if (i < j)
					{
						sl.block = info->block;
						for (int z = 0; z < kS; ++z)
						{
							uint64_t w = 0;
							for (std::size_t v = i; v < j; ++v) w |= h.mask[v][z];
							sl.in[z] = w;
						}
						// x + 1 is bit + 1, y + 1 is bit + 8 (x = 7 and y = 7 get garbage or 0 there).
						auto gx = [](uint64_t w) { return w | w >> 1; };
						auto gy = [](uint64_t w) { return w | w >> VoxelBlock::kSide; };
						for (int z = 0; z < kS; ++z)
						{
							const uint64_t zz = z + 1 < kS ? sl.in[z] | sl.in[z + 1] : sl.in[z];
							sl.near[0][z] = gx(gy(zz));
							sl.near[1][z] = gy(zz);
							sl.near[2][z] = gx(zz);
							sl.near[3][z] = gx(gy(sl.in[z]));
						}
					}
				}
			}
			return sl;
		};
		// Known source voxels a lookup through keyframe k from the block whose voxel centres
		// span [clo, chi] may read (in the travel window of k when the window is on), and their
		// bounding box [vlo, vhi] (voxel indices): the earlier positions of those centres lie in
		// the AABB of the mapped box (the map is affine), and lookups read at most one voxel
		// beyond (one more of margin for rounding). A count of 0 means no lookup through k
		// can succeed, so dropping k changes no result; a lookup whose corners all miss the box
		// cannot succeed either.
		struct Region
		{
			std::size_t count{0};
			VoxelIndex lo{INT32_MAX, INT32_MAX, INT32_MAX}, hi{INT32_MIN, INT32_MIN, INT32_MIN};
		};
		auto readableRegion = [&](const PreparedKeyframe& k, const mrpt::math::TPoint3D& clo,
								  const mrpt::math::TPoint3D& chi) {
			// The mapped box: image of the centre plus |rotation| times the half extents.
			const auto qc = k.newToOld({0.5 * (clo.x + chi.x), 0.5 * (clo.y + chi.y), 0.5 * (clo.z + chi.z)});
			const double e[3] = {0.5 * (chi.x - clo.x), 0.5 * (chi.y - clo.y), 0.5 * (chi.z - clo.z)};
			const double* B = k.newToOld.m;
			double lo[3] = {qc.x, qc.y, qc.z}, hi[3] = {qc.x, qc.y, qc.z};
			for (int a = 0; a < 3; ++a)
			{
				const double ext = std::abs(B[4 * a]) * e[0] + std::abs(B[4 * a + 1]) * e[1] + std::abs(B[4 * a + 2]) * e[2];
				lo[a] -= ext, hi[a] += ext;
			}
			const VoxelIndex vlo{floorToInt(lo[0] * invRes) - 2, floorToInt(lo[1] * invRes) - 2,
				floorToInt(lo[2] * invRes) - 2};
			const VoxelIndex vhi{floorToInt(hi[0] * invRes) + 2, floorToInt(hi[1] * invRes) + 2,
				floorToInt(hi[2] * invRes) + 2};
			const VoxelIndex blo = VoxelBlockGrid::blockOf(vlo), bhi = VoxelBlockGrid::blockOf(vhi);
			const auto& sets = travelSets[k.kf->submap];
			// 1e-6 m of slack keeps the test conservative against the rounding of the window.
			const bool window = opts.travelWindow > 0;
			const double wlo = k.kf->travelled - opts.travelWindow - 1e-6,
						 whi = k.kf->travelled + opts.travelWindow + 1e-6;
			Region r;
			for (int32_t z = blo.z; z <= bhi.z; ++z)
				for (int32_t y = blo.y; y <= bhi.y; ++y)
					for (int32_t x = blo.x; x <= bhi.x; ++x)
					{
						const SourceBlockInfo* info = sets.find({x, y, z});
						if (!info) continue;
						const TravelHistogram& h = info->travels;
						const auto [i, j] = window ? h.range(wlo, whi) : std::make_pair(std::size_t(0), h.travel.size());
						if (i == j) continue;
						r.count += h.count(i, j);
						const VoxelIndex f = VoxelBlockGrid::firstVoxelOf({x, y, z});
						for (std::size_t v = i; v < j; ++v)
						{
							const auto& b = h.box[v];
							r.lo = {std::min(r.lo.x, f.x + b[0]), std::min(r.lo.y, f.y + b[1]), std::min(r.lo.z, f.z + b[2])};
							r.hi = {std::max(r.hi.x, f.x + b[3]), std::max(r.hi.y, f.y + b[4]), std::max(r.hi.z, f.z + b[5])};
						}
					}
			return r;
		};
		for (std::size_t bi = b0; bi < b1; ++bi)
		{
			const VoxelIndex first = VoxelBlockGrid::firstVoxelOf(outBlocks[bi].first);
			const mrpt::math::TPoint3D blo(first.x * res, first.y * res, first.z * res);
			const mrpt::math::TPoint3D bhi(blo.x + blockEdge, blo.y + blockEdge, blo.z + blockEdge);
			// Centres of the first and last voxel: every voxel centre of the block is in [clo, chi].
			const mrpt::math::TPoint3D clo = centreOf(first),
									   chi = centreOf({first.x + kS - 1, first.y + kS - 1, first.z + kS - 1});
			const mrpt::math::TPoint3D bc(
				0.5 * (clo.x + chi.x), 0.5 * (clo.y + chi.y), 0.5 * (clo.z + chi.z));
			near.clear();
			for (const auto& k : kfs)
			{
				if (!(k.lo.x <= bhi.x && k.hi.x >= blo.x && k.lo.y <= bhi.y && k.hi.y >= blo.y &&
						k.lo.z <= bhi.z && k.hi.z >= blo.z))
					continue;
				const ConeOverlap ov = boxVsCone(k, clo, chi, maxRange2);
				if (ov == ConeOverlap::Outside) continue;
				const Region reg = readableRegion(k, clo, chi);
				if (reg.count == 0) continue;
				// Ranking score (only used with a keyframe limit): readable voxels times the
				// weight at the block centre, an estimate of the keyframe's share of the averages.
				const double dx = bc.x - k.centreNew.x, dy = bc.y - k.centreNew.y, dz = bc.z - k.centreNew.z;
				near.push_back({&k, ov == ConeOverlap::Partial,
					double(reg.count) * weightAt(dx * dx + dy * dy + dz * dz), reg.lo, reg.hi});
			}
			if (near.empty()) continue;
			if (opts.maxKeyframesPerBlock > 0 && near.size() > opts.maxKeyframesPerBlock)
			{
				// The K highest scores; ties by keyframe order. Then back to keyframe order, the
				// order every voxel sums in.
				auto closer = [](const Near& a, const Near& b) {
					return a.score != b.score ? a.score > b.score : a.k < b.k;
				};
				std::nth_element(near.begin(), near.begin() + (opts.maxKeyframesPerBlock - 1), near.end(), closer);
				near.resize(opts.maxKeyframesPerBlock);
				std::sort(near.begin(), near.end(), [](const Near& a, const Near& b) { return a.k < b.k; });
			}
			std::fill(sw.begin(), sw.end(), 0.0);
			std::fill(swl.begin(), swl.end(), 0.0);
			std::fill(bestW.begin(), bestW.end(), -1.0);
			ps.evaluatedVoxels += kN;
			ps.blockKeyframePairs += near.size();
			for (const Near& nk : near)
			{
				const PreparedKeyframe& k = *nk.k;
				cacheInfo = &travelSets[k.kf->submap];
				cacheWlo = k.kf->travelled - opts.travelWindow - 1e-6;
				cacheWhi = k.kf->travelled + opts.travelWindow + 1e-6;
				for (auto& c : cache) c.key = VoxelIndex{INT32_MIN, 0, 0};
				// Both maps are affine in the voxel's local index (lx, ly, lz): the camera-frame
				// position (for the cone test) and the earlier position in voxel units, shifted by
				// half a voxel so that integers are voxel centres (for the lookup).
				const auto pc0 = k.worldToCamNew(clo);
				const auto q0 = k.newToOld(clo);
				const double* A = k.worldToCamNew.m;
				const double* B = k.newToOld.m;
				const double qa[3] = {q0.x * invRes - 0.5, q0.y * invRes - 0.5, q0.z * invRes - 0.5};
				// Column c of B times res / res: the step of the earlier position per voxel index.
				const double g[3][3] = {{B[0], B[4], B[8]}, {B[1], B[5], B[9]}, {B[2], B[6], B[10]}};
				const double ca[3][3] = {{A[0] * res, A[4] * res, A[8] * res},
					{A[1] * res, A[5] * res, A[9] * res}, {A[2] * res, A[6] * res, A[10] * res}};
				const double tw = k.kf->travelled;
				const bool window = opts.travelWindow > 0;
				// Local copies: the stores of the loop below could alias the originals for the compiler.
				const double win = opts.travelWindow, vres = res;
				const double cn[3] = {k.centreNew.x, k.centreNew.y, k.centreNew.z};
				double planes[4][3];
				std::copy(&k.planes[0][0], &k.planes[0][0] + 12, &planes[0][0]);
				// Readable box with one voxel (plus rounding) of margin, in voxel-centre units.
				const double boxLo[3] = {nk.lo.x - 1.001, nk.lo.y - 1.001, nk.lo.z - 1.001};
				const double boxHi[3] = {nk.hi.x + 1.001, nk.hi.y + 1.001, nk.hi.z + 1.001};
				// The tests that decide which voxels are examined are affine in (lx, ly, lz): the earlier
				// position within one voxel of the readable box (6 tests) and, when the block straddles
				// the cone, in front of the camera and inside the 4 side planes (5 tests). They are
				// clipped per block along lz, per slice along ly and per row along lx.
				AffineTest tests[11];
				int nTests = 0;
				for (int a = 0; a < 3; ++a)
				{
					tests[nTests++] = AffineTest(qa[a], g[0][a], g[1][a], g[2][a], boxLo[a]);
					tests[nTests++] = AffineTest(-qa[a], -g[0][a], -g[1][a], -g[2][a], -boxHi[a]);
				}
				constexpr int nBoxTests = 6;
				if (nk.partial)
				{
					tests[nTests++] = AffineTest(pc0.z, ca[0][2], ca[1][2], ca[2][2], 0.0);
					for (const auto& n : k.planes)
					{
						auto dot = [&](const double* v) { return n[0] * v[0] + n[1] * v[1] + n[2] * v[2]; };
						const double p0[3] = {pc0.x, pc0.y, pc0.z};
						tests[nTests++] = AffineTest(dot(p0), dot(ca[0]), dot(ca[1]), dot(ca[2]), 0.0);
					}
				}
				double lzLo = 0, lzHi = kS - 1;
				for (int j = 0; j < nTests; ++j)
				{
					const AffineTest& t = tests[j];
					keepAtLeast(t.c + t.max[0] + t.max[1], t.a[2], t.inv[2], t.b, lzLo, lzHi);
				}
				if (lzHi < lzLo) continue;
				for (int lz = static_cast<int>(std::ceil(lzLo)); lz <= static_cast<int>(lzHi); ++lz)
				{
					double cz[11];
					double lyLo = 0, lyHi = kS - 1;
					for (int j = 0; j < nTests; ++j)
					{
						const AffineTest& t = tests[j];
						cz[j] = t.c + lz * t.a[2];
						keepAtLeast(cz[j] + t.max[0], t.a[1], t.inv[1], t.b, lyLo, lyHi);
					}
					if (lyHi < lyLo) continue;
					for (int ly = static_cast<int>(std::ceil(lyLo)); ly <= static_cast<int>(lyHi); ++ly)
					{
						// Along the row, the part where all tests may hold, and for the cone tests the
						// part where they hold by more than 1e-9 m, far more than the rounding of the
						// per-voxel evaluation: there the per-voxel cone tests cannot fail and are skipped.
						double lxLo = 0, lxHi = kS - 1, sureLo = 0, sureHi = kS - 1;
						for (int j = 0; j < nTests; ++j)
						{
							const AffineTest& t = tests[j];
							const double v0 = cz[j] + ly * t.a[1];
							keepAtLeast(v0, t.a[0], t.inv[0], t.b, lxLo, lxHi);
							if (j < nBoxTests) continue;
							const double u = (1e-9 - v0) * t.inv[0];
							if (t.a[0] > 0) sureLo = std::max(sureLo, u);
							else if (t.a[0] < 0) sureHi = std::min(sureHi, u);
							else if (v0 < 1e-9) sureHi = -1;
						}
						if (lxHi < lxLo) continue;
						const int lxBegin = static_cast<int>(std::ceil(lxLo));
						const int lxEnd = static_cast<int>(lxHi);
						for (int lx = lxBegin; lx <= lxEnd; ++lx)
						{
							const int li = VoxelBlock::linear(lx, ly, lz);
							// The voxel centre (as VoxelBlockGrid::centreOf) and its squared distance to the camera.
							const double X[3] = {(first.x + lx + 0.5) * vres, (first.y + ly + 0.5) * vres,
								(first.z + lz + 0.5) * vres};
							const double dz2 = (X[0] - cn[0]) * (X[0] - cn[0]) + (X[1] - cn[1]) * (X[1] - cn[1]) +
								(X[2] - cn[2]) * (X[2] - cn[2]);
							if (nk.partial)
							{
								// Inside the corrected cone: within range, in front, inside the 4 side planes of
								// the image pyramid (the pixel test without division).
								if (dz2 > maxRange2) continue;
								if (lx < sureLo || lx > sureHi)
								{
									const double px = pc0.x + lx * ca[0][0] + ly * ca[1][0] + lz * ca[2][0];
									const double py = pc0.y + lx * ca[0][1] + ly * ca[1][1] + lz * ca[2][1];
									const double pz = pc0.z + lx * ca[0][2] + ly * ca[1][2] + lz * ca[2][2];
									if (!(pz > 0)) continue;
									bool in = true;
									for (const auto& n : planes) in = in && n[0] * px + n[1] * py + n[2] * pz >= 0;
									if (!in) continue;
								}
							}
							// Earlier position in voxel units (the row is clipped to within one voxel of the
							// readable box: a lookup reads voxels within one of it).
							const double rx = qa[0] + lx * g[0][0] + ly * g[1][0] + lz * g[2][0];
							const double ry = qa[1] + lx * g[0][1] + ly * g[1][1] + lz * g[2][1];
							const double rz = qa[2] + lx * g[0][2] + ly * g[1][2] + lz * g[2][2];
							++ps.attemptedLookups;
							// Positions within 1e-6 voxel of a centre snap to it, so that an identity or
							// whole-voxel correction reads exactly one voxel (rounding of the composed pose).
							// r = nearest centre; trilinear corner x0 = floor(position), f its fraction.
							auto corners = [&](int32_t& x0, int32_t& y0, int32_t& z0, double& fx, double& fy, double& fz) {
								x0 = floorToInt(rx + 0.5), y0 = floorToInt(ry + 0.5), z0 = floorToInt(rz + 0.5);
								fx = fy = fz = 0;
								if (!trilinear) return;
								auto corner = [](double q, int32_t& i, double& f) {
									const double d = q - i;
									if (std::abs(d) < 1e-6) return;  // snapped: f = 0
									i -= d < 0;
									f = q - i;
								};
								corner(rx, x0, fx), corner(ry, y0, fy), corner(rz, z0, fz);
							};
							int32_t x0, y0, z0;
							double fx, fy, fz;
							double cw = 0, cl = 0, cbest = -1;
							float ctravel = 0;
							constexpr int m = kS - 1;
							// Every corner with a positive weight lies in the cube o + {0, 1}^3, o = floor(r):
							// o = x0, or x0 - 1 where r snapped up to x0 (then the corner x0 + 1 has weight 0).
							const int32_t ox = floorToInt(rx), oy = floorToInt(ry), oz = floorToInt(rz);
							if ((ox & m) != m && (oy & m) != m && (oz & m) != m)
							{
								// The cube in one source block (7 times in 8 per axis): no lookup when none of its
								// voxels is known in the window (dilated mask), else its 8 voxels at fixed offsets
								// without branches. Weights per axis: {1 - f, f} from o = x0, {0, 1} from
								// o = x0 - 1. A corner that does not count adds exactly 0, and the corners that
								// do keep their order, so the sums equal those of the general path below.
								const Slot& sl = sourceSlot(VoxelBlockGrid::blockOf(VoxelIndex{ox, oy, oz}));
								if (!sl.block || !((sl.near[0][oz & m] >> ((ox & m) + kS * (oy & m))) & 1)) continue;
								corners(x0, y0, z0, fx, fy, fz);
								const double wx[2] = {ox == x0 ? 1 - fx : 0.0, ox == x0 ? fx : 1.0};
								const double wy[2] = {oy == y0 ? 1 - fy : 0.0, oy == y0 ? fy : 1.0};
								const double wz[2] = {oz == z0 ? 1 - fz : 0.0, oz == z0 ? fz : 1.0};
								const Voxel* v0 = &sl.block->voxels[VoxelBlockGrid::localLinear({ox, oy, oz})];
								constexpr int off[8] = {0, 1, kS, kS + 1, kS * kS, kS * kS + 1, kS * kS + kS, kS * kS + kS + 1};
								for (int c = 0; c < 8; ++c)
								{
									const Voxel& src = v0[off[c]];
									const double tc = wx[c & 1] * wy[(c >> 1) & 1] * wz[c >> 2];
									const bool ok = (tc > 0) & src.isKnown() &
										(!window | (std::abs(double(src.travelled) - tw) <= win));
									const double tk = ok ? tc : 0.0;
									cw += tk;
									cl += tk * double(src.logOdds);
									const bool better = ok & (tc > cbest);
									cbest = better ? tc : cbest;
									ctravel = better ? src.travelled : ctravel;
								}
							}
							else
							{
								const int ex = (ox & m) == m, ey = (oy & m) == m, ez = (oz & m) == m;
								if (ex + ey + ez == 1)
								{
									// The cube crosses one block face (the common case here): its halves in
									// the two blocks, dilated along the other two axes, hold no known voxel in
									// the window -> no corner can count.
									const int a = ex ? 0 : ey ? 1 : 2;
									const VoxelIndex b1 = VoxelBlockGrid::blockOf(VoxelIndex{ox, oy, oz});
									const Slot& s1 = sourceSlot(b1);  // the two blocks differ in parity:
									const Slot& s2 = sourceSlot({b1.x + ex, b1.y + ey, b1.z + ez});  // two slots
									const int bit1 = (ox & m) + kS * (oy & m);
									const int bit2 = ex ? kS * (oy & m) : ey ? (ox & m) : bit1;
									if (!(s1.block && ((s1.near[1 + a][oz & m] >> bit1) & 1)) &&
										!(s2.block && ((s2.near[1 + a][ez ? 0 : oz & m] >> bit2) & 1)))
										continue;
								}
								corners(x0, y0, z0, fx, fy, fz);
								const double wx[2] = {1 - fx, fx}, wy[2] = {1 - fy, fy}, wz[2] = {1 - fz, fz};
								for (int c = 0; c < 8; ++c)
								{
									const double tc = wx[c & 1] * wy[(c >> 1) & 1] * wz[c >> 2];
									if (tc <= 0) continue;
									const VoxelIndex sv{x0 + (c & 1), y0 + ((c >> 1) & 1), z0 + ((c >> 2) & 1)};
									const Slot& sl = sourceSlot(VoxelBlockGrid::blockOf(sv));
									if (!sl.block || !((sl.in[sv.z & m] >> ((sv.x & m) + kS * (sv.y & m))) & 1))
										continue;
									const Voxel& src = sl.block->voxels[VoxelBlockGrid::localLinear(sv)];
									if (!src.isKnown()) continue;
									if (window && std::abs(double(src.travelled) - tw) > win) continue;
									cw += tc;
									cl += tc * double(src.logOdds);
									if (tc > cbest) cbest = tc, ctravel = src.travelled;
								}
							}
							if (cw < 0.5) continue;  // the earlier position is mostly unknown
							const double w = weightAt(dz2);
							sw[li] += w;
							swl[li] += w * (cl / cw);
							++ps.lookups;
							if (w > bestW[li])
							{
								bestW[li] = w;
								bestTravel[li] = ctravel;
							}
						}
					}
				}
			}
			VoxelBlock& blk = *outBlocks[bi].second;
			for (int li = 0; li < kN; ++li)
			{
				if (sw[li] <= 0) continue;
				Voxel& o = blk.voxels[li];
				o.logOdds = static_cast<float>(swl[li] / sw[li]);
				o.travelled = bestTravel[li];
				++ps.morphedVoxels;
			}
		}
		partial[t] = ps;
	});
	for (const auto& p : partial)
	{
		st.evaluatedVoxels += p.evaluatedVoxels;
		st.morphedVoxels += p.morphedVoxels;
		st.lookups += p.lookups;
		st.blockKeyframePairs += p.blockKeyframePairs;
		st.attemptedLookups += p.attemptedLookups;
	}
}

}  // namespace keygrid::detail::morphing
