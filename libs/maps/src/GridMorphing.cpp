#include "detail/Grid3DConfig.h"
#include "detail/Grid3DParallel.h"

#include <keygrid/maps/GridMorphing.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/system/CTicTac.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace keygrid
{
void MorphingOptions::loadFromConfigFile(
	const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	using detail::readNumber;
	viewConeMaxRange = readNumber(c, s, "morphViewConeMaxRange", viewConeMaxRange);
	travelWindow = readNumber(c, s, "morphTravelWindow", travelWindow);
	weightExponent = readNumber(c, s, "morphWeightExponent", weightExponent);
	minWeightDistance = readNumber(c, s, "morphMinWeightDistance", minWeightDistance);
	keepVoxelsOutsideCones = detail::readBool(c, s, "morphKeepVoxelsOutsideCones", keepVoxelsOutsideCones);
	const double th = readNumber(c, s, "morphThreads", threads);
	detail::require(th >= 0 && th == std::floor(th), "morphThreads", th, "an integer >= 0");
	threads = static_cast<unsigned>(th);
	const std::string interp = c.read_string(s, "morphInterpolation", "", false);
	if (interp == "nearest") interpolation = Interpolation::Nearest;
	else if (interp == "trilinear") interpolation = Interpolation::Trilinear;
	else if (!interp.empty())
		throw std::invalid_argument(
			"[" + s + "] morphInterpolation = '" + interp + "' (expected nearest or trilinear)");
	validate();
}

void MorphingOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	detail::writeNumber(c, s, "morphViewConeMaxRange", viewConeMaxRange);
	detail::writeNumber(c, s, "morphTravelWindow", travelWindow);
	detail::writeNumber(c, s, "morphWeightExponent", weightExponent);
	detail::writeNumber(c, s, "morphMinWeightDistance", minWeightDistance);
	detail::writeBool(c, s, "morphKeepVoxelsOutsideCones", keepVoxelsOutsideCones);
	detail::writeNumber(c, s, "morphThreads", threads);
	c.write(s, "morphInterpolation",
		std::string(interpolation == Interpolation::Nearest ? "nearest" : "trilinear"));
}

void MorphingOptions::validate() const
{
	detail::require(viewConeMaxRange > 0, "morphViewConeMaxRange", viewConeMaxRange, "> 0 m");
	detail::require(weightExponent >= 0, "morphWeightExponent", weightExponent, ">= 0");
	detail::require(travelWindow >= 0, "morphTravelWindow", travelWindow, ">= 0 m");
	detail::require(minWeightDistance > 0, "morphMinWeightDistance", minWeightDistance, "> 0 m");
}

namespace
{
/** Rigid transform as a 3x4 matrix: p' = R p + t. */
struct Rigid
{
	double m[12];
	explicit Rigid(const mrpt::poses::CPose3D& T)
	{
		const auto R = T.getRotationMatrix();
		for (int r = 0; r < 3; ++r)
		{
			for (int c = 0; c < 3; ++c) m[4 * r + c] = R(r, c);
			m[4 * r + 3] = T.m_coords[r];
		}
	}
	mrpt::math::TPoint3D operator()(const mrpt::math::TPoint3D& p) const
	{
		return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3],
			m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
			m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
	}
};

/** A corrected keyframe prepared for the per-voxel loop. */
struct PreparedKeyframe
{
	const MorphKeyframe* kf;
	const VoxelBlockGrid* grid;
	Rigid worldToCamNew;  //!< inv(T_new)
	Rigid newToOld;  //!< T_old * inv(T_new): corrected world -> old world
	Rigid oldToNew;  //!< T_new * inv(T_old)
	mrpt::math::TPoint3D centreNew;
	mrpt::math::TPoint3D lo, hi;  //!< AABB of the corrected view cone
	/** Inward unit normals (camera frame) of the 4 side planes of the image pyramid. */
	double planes[4][3];
};

/** Side planes of the pyramid through the camera centre and the image corners (u in {0, w},
 * v in {0, h}), oriented so that the image centre's ray is inside. */
void computePlanes(PreparedKeyframe& p)
{
	const auto& c = p.kf->camera;
	const double us[4] = {0.0, double(c.width), double(c.width), 0.0};
	const double vs[4] = {0.0, 0.0, double(c.height), double(c.height)};
	double r[4][3];
	for (int i = 0; i < 4; ++i)
		r[i][0] = (us[i] - c.cx) / c.fx, r[i][1] = (vs[i] - c.cy) / c.fy, r[i][2] = 1.0;
	const double mid[3] = {(c.width / 2.0 - c.cx) / c.fx, (c.height / 2.0 - c.cy) / c.fy, 1.0};
	for (int i = 0; i < 4; ++i)
	{
		const double* a = r[i];
		const double* b = r[(i + 1) % 4];
		double n[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
		const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
		const double sgn = (n[0] * mid[0] + n[1] * mid[1] + n[2] * mid[2]) < 0 ? -1.0 : 1.0;
		for (int k = 0; k < 3; ++k) p.planes[i][k] = sgn * n[k] / len;
	}
}

/** Where a sphere (world centre, radius) lies relative to the corrected view cone. */
enum class ConeOverlap
{
	Outside,
	Partial,
	Inside
};
ConeOverlap sphereVsCone(const PreparedKeyframe& k, const mrpt::math::TPoint3D& centre,
	double radius, double maxRange)
{
	const auto pc = k.worldToCamNew(centre);
	bool inside = pc.z >= radius;
	if (pc.z < -radius) return ConeOverlap::Outside;
	const double dist = std::sqrt(pc.x * pc.x + pc.y * pc.y + pc.z * pc.z);
	if (dist > maxRange + radius) return ConeOverlap::Outside;
	inside = inside && dist <= maxRange - radius;
	for (const auto& n : k.planes)
	{
		const double d = n[0] * pc.x + n[1] * pc.y + n[2] * pc.z;
		if (d < -radius) return ConeOverlap::Outside;
		inside = inside && d >= radius;
	}
	return inside ? ConeOverlap::Inside : ConeOverlap::Partial;
}

bool coneContains(const Rigid& w2c, const core::RgbdCamera& cam, double maxRange,
	const mrpt::math::TPoint3D& p)
{
	const auto pc = w2c(p);
	if (!(pc.z > 0)) return false;
	if (pc.x * pc.x + pc.y * pc.y + pc.z * pc.z > maxRange * maxRange) return false;
	const double u = cam.fx * pc.x / pc.z + cam.cx, v = cam.fy * pc.y / pc.z + cam.cy;
	return u >= 0 && v >= 0 && u < cam.width && v < cam.height;
}
}  // namespace

bool insideViewCone(const mrpt::math::TPoint3D& p, const mrpt::poses::CPose3D& T_world_cam,
	const core::RgbdCamera& cam, double maxRange)
{
	return coneContains(Rigid(-T_world_cam), cam, maxRange, p);
}

VoxelBlockGrid morphAndMerge(const std::vector<const VoxelBlockGrid*>& sources,
	const std::vector<MorphKeyframe>& keyframes, const MorphingOptions& opts, MorphingStats* stats)
{
	opts.validate();
	mrpt::system::CTicTac timer;
	if (sources.empty()) throw std::invalid_argument("morphAndMerge: no source grid");
	const double res = sources.front()->resolution();
	for (const auto* g : sources)
		if (!g || g->resolution() != res)
			throw std::invalid_argument("morphAndMerge: source grids differ in resolution");

	// Keyframes per submap, sorted by travelled distance (to find a voxel's last updater).
	std::vector<PreparedKeyframe> kfs;
	kfs.reserve(keyframes.size());
	std::vector<std::vector<std::pair<double, std::size_t>>> byTravel(sources.size());
	for (const auto& kf : keyframes)
	{
		if (kf.submap >= sources.size())
			throw std::invalid_argument(
				"morphAndMerge: keyframe " + std::to_string(kf.id) + " refers to submap " +
				std::to_string(kf.submap) + " of " + std::to_string(sources.size()));
		PreparedKeyframe p{&kf, sources[kf.submap], Rigid(-kf.T_world_cam_new),
			Rigid(kf.T_world_cam_old + (-kf.T_world_cam_new)),
			Rigid(kf.T_world_cam_new + (-kf.T_world_cam_old)),
			mrpt::math::TPoint3D(
				kf.T_world_cam_new.x(), kf.T_world_cam_new.y(), kf.T_world_cam_new.z()),
			{}, {}, {}};
		p.lo = p.hi = p.centreNew;
		const double R = opts.viewConeMaxRange;
		for (double u : {0.0, double(kf.camera.width)})
			for (double v : {0.0, double(kf.camera.height)})
			{
				// Far corner of the pyramid at depth R (contains the range-limited cone).
				const mrpt::math::TPoint3D pc(
					(u - kf.camera.cx) / kf.camera.fx * R, (v - kf.camera.cy) / kf.camera.fy * R, R);
				const auto pw = kf.T_world_cam_new.composePoint(pc);
				p.lo = {std::min(p.lo.x, pw.x), std::min(p.lo.y, pw.y), std::min(p.lo.z, pw.z)};
				p.hi = {std::max(p.hi.x, pw.x), std::max(p.hi.y, pw.y), std::max(p.hi.z, pw.z)};
			}
		computePlanes(p);
		byTravel[kf.submap].emplace_back(kf.travelled, kfs.size());
		kfs.push_back(p);
	}
	for (auto& v : byTravel) std::sort(v.begin(), v.end());

	// Keyframe of submap s whose travelled distance is closest to t (nullptr if none).
	auto lastUpdater = [&](std::size_t s, double t) -> const PreparedKeyframe* {
		const auto& v = byTravel[s];
		if (v.empty()) return nullptr;
		auto it = std::lower_bound(
			v.begin(), v.end(), std::make_pair(t, std::size_t(0)));
		if (it == v.end()) return &kfs[std::prev(it)->second];
		if (it != v.begin() && std::abs(std::prev(it)->first - t) <= std::abs(it->first - t))
			--it;
		return &kfs[it->second];
	};
	auto forward = [&](const PreparedKeyframe* k, const mrpt::math::TPoint3D& p) {
		return k ? k->oldToNew(p) : p;
	};

	VoxelBlockGrid out(res);
	MorphingStats st;

	// 1. Allocate the corrected blocks touched by the forward images of the source blocks, and
	// note which travelled distances each source block's known voxels carry, as a 64-bit mask of
	// travel bins (step 2 uses it to skip keyframes whose travel window no voxel of the blocks
	// they would read can pass; conservative, so it changes no result).
	const double blockEdge = res * VoxelBlock::kSide;
	double travelMax = 0;
	for (const auto& kf : keyframes) travelMax = std::max(travelMax, kf.travelled);
	for (const auto* g : sources)
		g->forEachKnown([&](const VoxelIndex&, const Voxel& v) { travelMax = std::max(travelMax, double(v.travelled)); });
	const double binWidth = std::max({opts.travelWindow, travelMax / 64.0, 1e-9});
	auto travelBin = [&](double t) { return std::clamp(static_cast<int>(std::floor(t / binWidth)), 0, 63); };
	std::vector<std::unordered_map<VoxelIndex, uint64_t, VoxelIndexHash>> travelBins(sources.size());
	for (std::size_t s = 0; s < sources.size(); ++s)
	{
		travelBins[s].reserve(sources[s]->numBlocks());
		for (const auto& [bidx, blk] : sources[s]->blocks())
		{
			std::vector<const PreparedKeyframe*> used;
			uint64_t bins = 0;
			for (const Voxel& v : blk->voxels)
			{
				if (!v.isKnown()) continue;
				bins |= uint64_t(1) << travelBin(v.travelled);
				++st.sourceVoxels;
				const PreparedKeyframe* k = lastUpdater(s, v.travelled);
				if (std::find(used.begin(), used.end(), k) == used.end()) used.push_back(k);
			}
			if (!used.empty()) travelBins[s].emplace(bidx, bins);
			const VoxelIndex first = VoxelBlockGrid::firstVoxelOf(bidx);
			for (const PreparedKeyframe* k : used)
			{
				mrpt::math::TPoint3D lo(1e300, 1e300, 1e300), hi(-1e300, -1e300, -1e300);
				for (int c = 0; c < 8; ++c)
				{
					const mrpt::math::TPoint3D corner(first.x * res + ((c & 1) ? blockEdge : 0),
						first.y * res + ((c & 2) ? blockEdge : 0),
						first.z * res + ((c & 4) ? blockEdge : 0));
					const auto q = forward(k, corner);
					lo = {std::min(lo.x, q.x), std::min(lo.y, q.y), std::min(lo.z, q.z)};
					hi = {std::max(hi.x, q.x), std::max(hi.y, q.y), std::max(hi.z, q.z)};
				}
				const VoxelIndex blo = VoxelBlockGrid::blockOf(out.voxelOf(lo));
				const VoxelIndex bhi = VoxelBlockGrid::blockOf(out.voxelOf(hi));
				for (int32_t z = blo.z; z <= bhi.z; ++z)
					for (int32_t y = blo.y; y <= bhi.y; ++y)
						for (int32_t x = blo.x; x <= bhi.x; ++x) out.blockAt({x, y, z});
			}
		}
	}

	// 2. Weighted average of the earlier log-odds over the corrected cones containing each voxel.
	std::vector<std::pair<VoxelIndex, VoxelBlock*>> outBlocks;
	outBlocks.reserve(out.numBlocks());
	for (const auto& [b, blk] : out.blocks()) outBlocks.emplace_back(b, blk.get());
	std::sort(outBlocks.begin(), outBlocks.end(),
		[](const auto& a, const auto& b) { return a.first < b.first; });

	const unsigned nt = detail::resolveThreads(opts.threads);
	std::vector<MorphingStats> partial(nt);
	const double zMin = opts.minWeightDistance, pw = opts.weightExponent, invRes = 1.0 / res;
	const bool trilinear = opts.interpolation == MorphingOptions::Interpolation::Trilinear;
	detail::parallelChunks(outBlocks.size(), nt, [&](std::size_t b0, std::size_t b1, unsigned t) {
		MorphingStats& ps = partial[t];
		// Keyframes whose cone meets the block; `partial` ones need the per-voxel cone test.
		// Each keeps the last source block it read (neighbouring voxels read the same block).
		struct Near
		{
			const PreparedKeyframe* k;
			bool partial;
			/** Source blocks read through this keyframe, direct-mapped by the parity of the
			 * block coordinates: the (up to 8) blocks of one trilinear lookup never collide. */
			VoxelIndex cacheKey[8];
			const VoxelBlock* cachePtr[8];

			const VoxelBlock* block(const VoxelIndex& b)
			{
				const int slot = (b.x & 1) | ((b.y & 1) << 1) | ((b.z & 1) << 2);
				if (cacheKey[slot] != b)
				{
					cacheKey[slot] = b;
					cachePtr[slot] = k->grid->findBlock(b);
				}
				return cachePtr[slot];
			}
		};
		std::vector<Near> near;
		const double radius = 0.5 * std::sqrt(3.0) * blockEdge;
		// Can a lookup through keyframe k from the block centred at bc pass the travel window?
		// Its voxels' earlier positions lie within `radius` of newToOld(bc) (rigid map), their
		// trilinear neighbours within one more voxel: any source block there with a known voxel
		// in a travel bin of [s_k - W, s_k + W] keeps k. Dropping k otherwise changes no result.
		auto travelWindowReachable = [&](const PreparedKeyframe& k, const mrpt::math::TPoint3D& bc) {
			const auto c = k.newToOld(bc);
			const double r = radius + 1.01 * res;
			const VoxelBlockGrid& g = *k.grid;
			const VoxelIndex lo = VoxelBlockGrid::blockOf(g.voxelOf({c.x - r, c.y - r, c.z - r}));
			const VoxelIndex hi = VoxelBlockGrid::blockOf(g.voxelOf({c.x + r, c.y + r, c.z + r}));
			const auto& bins = travelBins[k.kf->submap];
			// Bins of [s_k - W, s_k + W] (a voxel passes the window only if its bin is one of them).
			const int b0 = travelBin(k.kf->travelled - opts.travelWindow), b1 = travelBin(k.kf->travelled + opts.travelWindow);
			const uint64_t want = (b1 == 63 ? ~uint64_t(0) : (uint64_t(1) << (b1 + 1)) - 1) & ~((uint64_t(1) << b0) - 1);
			for (int32_t z = lo.z; z <= hi.z; ++z)
				for (int32_t y = lo.y; y <= hi.y; ++y)
					for (int32_t x = lo.x; x <= hi.x; ++x)
					{
						const auto it = bins.find({x, y, z});
						if (it != bins.end() && (it->second & want)) return true;
					}
			return false;
		};
		for (std::size_t bi = b0; bi < b1; ++bi)
		{
			const VoxelIndex first = VoxelBlockGrid::firstVoxelOf(outBlocks[bi].first);
			const mrpt::math::TPoint3D blo(first.x * res, first.y * res, first.z * res);
			const mrpt::math::TPoint3D bhi(blo.x + blockEdge, blo.y + blockEdge, blo.z + blockEdge);
			const mrpt::math::TPoint3D bc(
				blo.x + 0.5 * blockEdge, blo.y + 0.5 * blockEdge, blo.z + 0.5 * blockEdge);
			near.clear();
			for (const auto& k : kfs)
			{
				if (!(k.lo.x <= bhi.x && k.hi.x >= blo.x && k.lo.y <= bhi.y && k.hi.y >= blo.y &&
						k.lo.z <= bhi.z && k.hi.z >= blo.z))
					continue;
				const ConeOverlap ov = sphereVsCone(k, bc, radius, opts.viewConeMaxRange);
				if (ov == ConeOverlap::Outside) continue;
				if (opts.travelWindow > 0 && !travelWindowReachable(k, bc))
					continue;  // every lookup through k would fail the travel window
				{
					Near nk{&k, ov == ConeOverlap::Partial, {}, {}};
					for (int c = 0; c < 8; ++c) nk.cacheKey[c] = VoxelIndex{INT32_MIN, 0, 0}, nk.cachePtr[c] = nullptr;
					near.push_back(nk);
				}
			}
			if (near.empty()) continue;
			VoxelBlock& blk = *outBlocks[bi].second;
			for (int lz = 0; lz < VoxelBlock::kSide; ++lz)
				for (int ly = 0; ly < VoxelBlock::kSide; ++ly)
					for (int lx = 0; lx < VoxelBlock::kSide; ++lx)
					{
						const VoxelIndex vi{first.x + lx, first.y + ly, first.z + lz};
						const auto X = out.centreOf(vi);
						++ps.evaluatedVoxels;
						double sw = 0, swl = 0, bestW = -1;
						float bestTravel = 0;
						for (Near& nk : near)
						{
							const PreparedKeyframe* k = nk.k;
							if (nk.partial &&
								!coneContains(k->worldToCamNew, k->kf->camera, opts.viewConeMaxRange, X))
								continue;
							// Earlier position, trilinear over the known voxel centres around it.
							const auto P = k->newToOld(X);
							// Positions within 1e-6 voxel of a centre snap to it, so that an identity or
							// whole-voxel correction reads exactly one voxel (rounding of the composed pose).
							auto snap = [](double q) {
								const double r = std::nearbyint(q);
								return std::abs(q - r) < 1e-6 ? r : q;
							};
							const double px = snap(P.x * invRes - 0.5), py = snap(P.y * invRes - 0.5),
										 pz = snap(P.z * invRes - 0.5);
							int32_t x0 = floorToInt(px), y0 = floorToInt(py), z0 = floorToInt(pz);
							double fx = px - x0, fy = py - y0, fz = pz - z0;
							if (!trilinear)
							{
								// Nearest voxel: the one corner whose weight is 1.
								const VoxelIndex nv = k->grid->voxelOf(P);
								x0 = nv.x, y0 = nv.y, z0 = nv.z;
								fx = fy = fz = 0.0;
							}
							double cw = 0, cl = 0, cbest = -1;
							float ctravel = 0;
							// All 8 corners in one source block (7 times in 8 per axis): one block lookup.
							constexpr int m = VoxelBlock::kSide - 1;
							const VoxelBlock* oneBlock = nullptr;
							const bool sameBlock = (x0 & m) != m && (y0 & m) != m && (z0 & m) != m;
							if (sameBlock)
							{
								oneBlock = nk.block(VoxelBlockGrid::blockOf(VoxelIndex{x0, y0, z0}));
								if (!oneBlock) continue;
							}
							for (int c = 0; c < 8; ++c)
							{
								const VoxelIndex sv{x0 + (c & 1), y0 + ((c >> 1) & 1), z0 + ((c >> 2) & 1)};
								const double t = ((c & 1) ? fx : 1 - fx) * ((c & 2) ? fy : 1 - fy) * ((c & 4) ? fz : 1 - fz);
								if (t <= 0) continue;
								const VoxelBlock* sblk = sameBlock ? oneBlock : nk.block(VoxelBlockGrid::blockOf(sv));
								if (!sblk) continue;
								const Voxel& src = sblk->voxels[VoxelBlockGrid::localLinear(sv)];
								if (!src.isKnown()) continue;
								if (opts.travelWindow > 0 &&
									std::abs(double(src.travelled) - k->kf->travelled) > opts.travelWindow)
									continue;
								cw += t;
								cl += t * double(src.logOdds);
								if (t > cbest) cbest = t, ctravel = src.travelled;
							}
							if (cw < 0.5) continue;  // the earlier position is mostly unknown
							const double Li = cl / cw;
							const double dz2 = (X.x - k->centreNew.x) * (X.x - k->centreNew.x) +
								(X.y - k->centreNew.y) * (X.y - k->centreNew.y) +
								(X.z - k->centreNew.z) * (X.z - k->centreNew.z);
							// w = max(z, zMin)^-p; p = 2 (default) without pow / sqrt.
							const double w = pw == 2.0 ? 1.0 / std::max(dz2, zMin * zMin)
													   : std::pow(std::max(std::sqrt(dz2), zMin), -pw);
							sw += w;
							swl += w * Li;
							++ps.lookups;
							if (w > bestW)
							{
								bestW = w;
								bestTravel = ctravel;
							}
						}
						if (sw <= 0) continue;
						Voxel& o = blk.at(lx, ly, lz);
						o.logOdds = static_cast<float>(swl / sw);
						o.travelled = bestTravel;
						++ps.morphedVoxels;
					}
		}
	});
	for (const auto& p : partial)
	{
		st.evaluatedVoxels += p.evaluatedVoxels;
		st.morphedVoxels += p.morphedVoxels;
		st.lookups += p.lookups;
	}

	// 3. Voxels no cone gave a value keep their own, moved with their last updater's correction.
	if (opts.keepVoxelsOutsideCones)
	{
		for (std::size_t s = 0; s < sources.size(); ++s)
			sources[s]->forEachKnown([&](const VoxelIndex& vi, const Voxel& v) {
				const auto X = forward(lastUpdater(s, v.travelled), sources[s]->centreOf(vi));
				Voxel& o = out.at(out.voxelOf(X));
				if (o.isKnown()) return;
				o = v;
				++st.carriedVoxels;
			});
	}

	// 4. Drop blocks that stayed unknown.
	std::vector<VoxelIndex> empty;
	for (const auto& [b, blk] : out.blocks())
		if (std::none_of(blk->voxels.begin(), blk->voxels.end(),
				[](const Voxel& v) { return v.isKnown(); }))
			empty.push_back(b);
	VoxelBlockGrid pruned(res);
	if (!empty.empty())
	{
		std::sort(empty.begin(), empty.end());
		for (const auto& [b, blk] : out.blocks())
			if (!std::binary_search(empty.begin(), empty.end(), b)) pruned.blockAt(b) = *blk;
		out = std::move(pruned);
	}
	st.seconds = timer.Tac();
	if (stats) *stats = st;
	return out;
}

}  // namespace keygrid
