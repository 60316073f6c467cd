#include "detail/GridMorphingDetail.h"
#include "detail/OptionValues.h"

#include <keygrid/maps/GridMorphing.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/system/CTicTac.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace keygrid
{
core::OptionFields MorphingOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("morphViewConeMaxRange", viewConeMaxRange, "morphing: depth of each keyframe's view cone [m]", R::positive());
	f.add("morphTravelWindow", travelWindow, "morphing: a lookup through a keyframe counts only for voxels updated within this travel of it [m], 0 = off", R::atLeast(0));
	f.add("morphWeightExponent", weightExponent, "morphing: exponent p of a keyframe's weight 1 / max(z, morphMinWeightDistance)^p, z = distance to its camera", R::atLeast(0));
	f.add("morphMinWeightDistance", minWeightDistance, "morphing: distances below this count as this in the weights [m]", R::positive());
	f.addCustom("morphKeepVoxelsOutsideCones", detail::flagValue(keepVoxelsOutsideCones), "morphing: voxels no view cone gives a value move with their last updater's correction (false: dropped)");
	f.add("morphMaxKeyframesPerBlock", maxKeyframesPerBlock, "morphing: at most this many keyframes per 8^3 block (an approximation), 0 = all", R::inRange(0, 1000000));
	f.add("morphThreads", threads, "morphing worker threads, 0 = all hardware threads (same result for any count)");
	detail::addWords(
		f, "morphInterpolation", interpolation, {{"nearest", Interpolation::Nearest}, {"trilinear", Interpolation::Trilinear}},
		"morphing: how a keyframe reads a voxel at its earlier position: nearest voxel, or trilinear over the 8 around it");
	return f;
}

void MorphingOptions::validate(const std::string& s) const { core::validateFields(*this, s); }

using namespace detail::morphing;

namespace
{
/** Side planes of the pyramid through the camera centre and the image corners (u in {0, w},
 * v in {0, h}), oriented so that the image centre's ray is inside. */
void computePlanes(PreparedKeyframe& p)
{
	const auto& c = p.kf->camera;
	const core::PinholeIntrinsics K = c.pinhole();
	const double us[4] = {0.0, double(c.width), double(c.width), 0.0};
	const double vs[4] = {0.0, 0.0, double(c.height), double(c.height)};
	double r[4][3];
	for (int i = 0; i < 4; ++i)
		r[i][0] = K.rayX(us[i]), r[i][1] = K.rayY(vs[i]), r[i][2] = 1.0;
	const double mid[3] = {K.rayX(c.width / 2.0), K.rayY(c.height / 2.0), 1.0};
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
			{}, {}, {}, {}};
		p.lo = p.hi = p.centreNew;
		const double R = opts.viewConeMaxRange;
		for (double u : {0.0, double(kf.camera.width)})
			for (double v : {0.0, double(kf.camera.height)})
			{
				// Far corner of the pyramid at depth R (contains the range-limited cone).
				const Eigen::Vector3d p_cam = kf.camera.pinhole().backProject(u, v, R);
				const mrpt::math::TPoint3D pc(p_cam.x(), p_cam.y(), p_cam.z());
				const auto pw = kf.T_world_cam_new.composePoint(pc);
				p.lo = {std::min(p.lo.x, pw.x), std::min(p.lo.y, pw.y), std::min(p.lo.z, pw.z)};
				p.hi = {std::max(p.hi.x, pw.x), std::max(p.hi.y, pw.y), std::max(p.hi.z, pw.z)};
			}
		computePlanes(p);
		for (int f = 0; f < 5; ++f)
		{
			// Camera-frame normal n -> world R n; worldToCamNew holds R^T, so (R n)_i = sum_j m[4 j + i] n_j.
			const double z[3] = {0, 0, 1};
			const double* n = f == 0 ? z : p.planes[f - 1];
			for (int i = 0; i < 3; ++i)
				p.face[f][i] = p.worldToCamNew.m[i] * n[0] + p.worldToCamNew.m[4 + i] * n[1] +
					p.worldToCamNew.m[8 + i] * n[2];
		}
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
	// note the travelled distances each source block's known voxels carry (step 2 uses them to
	// skip keyframes whose travel window no voxel of the blocks they would read passes, and to
	// rank keyframes by how many voxels they can read).
	const double blockEdge = res * VoxelBlock::kSide;
	std::vector<SourceIndex> travelSets;  // moving one keeps its map's nodes, so pointers stay valid
	travelSets.reserve(sources.size());
	for (std::size_t s = 0; s < sources.size(); ++s)
	{
		std::unordered_map<VoxelIndex, SourceBlockInfo, VoxelIndexHash> infos;
		infos.reserve(sources[s]->numBlocks());
		for (const auto& [bidx, blk] : sources[s]->blocks())
		{
			std::vector<const PreparedKeyframe*> used;
			std::vector<std::pair<float, int>> travels;  // (travelled, local voxel index)
			for (int li = 0; li < VoxelBlock::kVoxels; ++li)
			{
				const Voxel& v = blk->voxels[li];
				if (!v.isKnown()) continue;
				travels.emplace_back(v.travelled, li);
				++st.sourceVoxels;
			}
			if (!travels.empty())
			{
				std::sort(travels.begin(), travels.end());
				TravelHistogram h;
				for (std::size_t i = 0; i < travels.size(); ++i)
				{
					const int li = travels[i].second;
					constexpr int side = VoxelBlock::kSide;
					const uint8_t x = li % side, y = (li / side) % side, z = li / (side * side);
					if (i == 0 || travels[i].first != travels[i - 1].first)
					{
						const PreparedKeyframe* k = lastUpdater(s, travels[i].first);
						if (std::find(used.begin(), used.end(), k) == used.end()) used.push_back(k);
						h.travel.push_back(travels[i].first);
						h.cumCount.push_back(0);
						h.box.push_back({x, y, z, x, y, z});
						h.mask.push_back({});
					}
					h.cumCount.back() = static_cast<uint32_t>(i + 1);
					h.mask.back()[z] |= uint64_t(1) << (x + side * y);
					auto& b = h.box.back();
					b[0] = std::min(b[0], x), b[1] = std::min(b[1], y), b[2] = std::min(b[2], z);
					b[3] = std::max(b[3], x), b[4] = std::max(b[4], y), b[5] = std::max(b[5], z);
				}
				infos.emplace(bidx, SourceBlockInfo{blk.get(), std::move(h)});
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
		travelSets.emplace_back(std::move(infos));
	}

	// 2. Weighted average of the earlier log-odds over the corrected cones containing each voxel.
	std::vector<std::pair<VoxelIndex, VoxelBlock*>> outBlocks;
	outBlocks.reserve(out.numBlocks());
	for (const auto& [b, blk] : out.blocks()) outBlocks.emplace_back(b, blk.get());
	std::sort(outBlocks.begin(), outBlocks.end(),
		[](const auto& a, const auto& b) { return a.first < b.first; });

	averageOverCones(outBlocks, kfs, travelSets, opts, res, st);

	// 3. Voxels no cone gave a value keep their own, moved with their last updater's correction.
	if (opts.keepVoxelsOutsideCones)
	{
		constexpr int kS = VoxelBlock::kSide;
		// In forEachKnown's order (blocks in hash-map order, x fastest), with the last updater
		// and the output block cached between consecutive voxels.
		for (std::size_t s = 0; s < sources.size(); ++s)
			for (const auto& [bidx, blk] : sources[s]->blocks())
			{
				const VoxelIndex first = VoxelBlockGrid::firstVoxelOf(bidx);
				float lastT = -2.0f;
				const PreparedKeyframe* k = nullptr;
				VoxelIndex outKey{INT32_MIN, 0, 0};
				VoxelBlock* outBlk = nullptr;
				for (int li = 0; li < VoxelBlock::kVoxels; ++li)
				{
					const Voxel& v = blk->voxels[li];
					if (!v.isKnown()) continue;
					if (v.travelled != lastT) lastT = v.travelled, k = lastUpdater(s, v.travelled);
					const VoxelIndex vi{first.x + li % kS, first.y + (li / kS) % kS, first.z + li / (kS * kS)};
					const VoxelIndex oi = out.voxelOf(forward(k, sources[s]->centreOf(vi)));
					const VoxelIndex ob = VoxelBlockGrid::blockOf(oi);
					if (ob != outKey) outKey = ob, outBlk = &out.blockAt(ob);
					Voxel& o = outBlk->voxels[VoxelBlockGrid::localLinear(oi)];
					if (o.isKnown()) continue;
					o = v;
					++st.carriedVoxels;
				}
			}
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
