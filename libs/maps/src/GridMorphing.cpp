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

	// 1. Allocate the corrected blocks touched by the forward images of the source blocks.
	const double blockEdge = res * VoxelBlock::kSide;
	for (std::size_t s = 0; s < sources.size(); ++s)
	{
		for (const auto& [bidx, blk] : sources[s]->blocks())
		{
			std::vector<const PreparedKeyframe*> used;
			for (const Voxel& v : blk->voxels)
			{
				if (!v.isKnown()) continue;
				++st.sourceVoxels;
				const PreparedKeyframe* k = lastUpdater(s, v.travelled);
				if (std::find(used.begin(), used.end(), k) == used.end()) used.push_back(k);
			}
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
	const double zMin = opts.minWeightDistance, pw = opts.weightExponent;
	detail::parallelChunks(outBlocks.size(), nt, [&](std::size_t b0, std::size_t b1, unsigned t) {
		MorphingStats& ps = partial[t];
		// Keyframes whose cone meets the block; `partial` ones need the per-voxel cone test.
		// Each keeps the last source block it read (neighbouring voxels read the same block).
		struct Near
		{
			const PreparedKeyframe* k;
			bool partial;
			VoxelIndex lastBlock;
			const VoxelBlock* lastPtr;
		};
		std::vector<Near> near;
		const double radius = 0.5 * std::sqrt(3.0) * blockEdge;
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
				if (ov != ConeOverlap::Outside)
					near.push_back({&k, ov == ConeOverlap::Partial, VoxelIndex{INT32_MIN, 0, 0}, nullptr});
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
							const VoxelIndex sv = k->grid->voxelOf(k->newToOld(X));
							const VoxelIndex sb = VoxelBlockGrid::blockOf(sv);
							if (sb != nk.lastBlock)
							{
								nk.lastBlock = sb;
								nk.lastPtr = k->grid->findBlock(sb);
							}
							if (!nk.lastPtr) continue;
							const Voxel* src = &nk.lastPtr->voxels[VoxelBlockGrid::localLinear(sv)];
							if (!src->isKnown()) continue;
							// Only content placed near keyframe i along the trajectory follows i's
							// correction (see travelWindow).
							if (opts.travelWindow > 0 &&
								std::abs(double(src->travelled) - k->kf->travelled) > opts.travelWindow)
								continue;
							const double dz = std::sqrt((X.x - k->centreNew.x) * (X.x - k->centreNew.x) +
								(X.y - k->centreNew.y) * (X.y - k->centreNew.y) +
								(X.z - k->centreNew.z) * (X.z - k->centreNew.z));
							const double w = std::pow(std::max(dz, zMin), -pw);
							sw += w;
							swl += w * double(src->logOdds);
							++ps.lookups;
							if (w > bestW)
							{
								bestW = w;
								bestTravel = src->travelled;
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
