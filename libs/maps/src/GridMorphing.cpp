#include "detail/Grid3DConfig.h"
#include "detail/Grid3DParallel.h"

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
void MorphingOptions::loadFromConfigFile(
	const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	using detail::readNumber;
	viewConeMaxRange = readNumber(c, s, "morphViewConeMaxRange", viewConeMaxRange);
	travelWindow = readNumber(c, s, "morphTravelWindow", travelWindow);
	weightExponent = readNumber(c, s, "morphWeightExponent", weightExponent);
	minWeightDistance = readNumber(c, s, "morphMinWeightDistance", minWeightDistance);
	keepVoxelsOutsideCones = detail::readBool(c, s, "morphKeepVoxelsOutsideCones", keepVoxelsOutsideCones);
	const double kmax = readNumber(c, s, "morphMaxKeyframesPerBlock", maxKeyframesPerBlock);
	detail::require(kmax >= 0 && kmax == std::floor(kmax) && kmax <= 1e6, "morphMaxKeyframesPerBlock",
		kmax, "an integer in [0, 1000000]");
	maxKeyframesPerBlock = static_cast<unsigned>(kmax);
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
	detail::writeNumber(c, s, "morphMaxKeyframesPerBlock", maxKeyframesPerBlock);
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

/** Travelled distances of the known voxels of one source block: distinct values, ascending,
 * and the number of voxels with a value <= each. */
struct TravelHistogram
{
	std::vector<float> travel;
	std::vector<uint32_t> cumCount;
	/** Per distinct value: bounding box of its voxels, local indices in [0, kSide): lo x y z,
	 * hi x y z. */
	std::vector<std::array<uint8_t, 6>> box;

	/** Indices [i, j) of the distinct values in [lo, hi]. */
	std::pair<std::size_t, std::size_t> range(double lo, double hi) const
	{
		auto less = [](float a, double b) { return double(a) < b; };
		const std::size_t i = std::lower_bound(travel.begin(), travel.end(), lo, less) - travel.begin();
		const std::size_t j = std::upper_bound(travel.begin(), travel.end(), hi,
								  [](double b, float a) { return b < double(a); }) - travel.begin();
		return {i, std::max(i, j)};
	}

	/** Voxels with the distinct values [i, j). */
	std::size_t count(std::size_t i, std::size_t j) const
	{
		return j <= i ? 0 : cumCount[j - 1] - (i > 0 ? cumCount[i - 1] : 0);
	}
};

/** What step 2 needs of one source block. */
struct SourceBlockInfo
{
	const VoxelBlock* block;
	TravelHistogram travels;
};

/** Source block infos by block index: a dense array over the blocks' bounding box when that
 * holds at most 2^20 blocks (rooms to buildings at 5 cm), else the hash map. */
class SourceIndex
{
   public:
	explicit SourceIndex(std::unordered_map<VoxelIndex, SourceBlockInfo, VoxelIndexHash>&& m)
		: m_map(std::move(m))
	{
		if (m_map.empty()) return;
		m_lo = m_hi = m_map.begin()->first;
		for (const auto& kv : m_map)
		{
			const VoxelIndex& b = kv.first;
			m_lo = {std::min(m_lo.x, b.x), std::min(m_lo.y, b.y), std::min(m_lo.z, b.z)};
			m_hi = {std::max(m_hi.x, b.x), std::max(m_hi.y, b.y), std::max(m_hi.z, b.z)};
		}
		m_nx = int64_t(m_hi.x) - m_lo.x + 1, m_ny = int64_t(m_hi.y) - m_lo.y + 1;
		const int64_t cells = m_nx * m_ny * (int64_t(m_hi.z) - m_lo.z + 1);
		if (cells > (int64_t(1) << 20)) return;
		m_dense.assign(static_cast<std::size_t>(cells), nullptr);
		for (const auto& kv : m_map) m_dense[cell(kv.first)] = &kv.second;
	}
	const SourceBlockInfo* find(const VoxelIndex& b) const
	{
		if (m_dense.empty())
		{
			const auto it = m_map.find(b);
			return it == m_map.end() ? nullptr : &it->second;
		}
		if (b.x < m_lo.x || b.y < m_lo.y || b.z < m_lo.z || b.x > m_hi.x || b.y > m_hi.y || b.z > m_hi.z)
			return nullptr;
		return m_dense[cell(b)];
	}

   private:
	std::size_t cell(const VoxelIndex& b) const
	{
		return static_cast<std::size_t>(((int64_t(b.z) - m_lo.z) * m_ny + (int64_t(b.y) - m_lo.y)) * m_nx +
			(int64_t(b.x) - m_lo.x));
	}
	std::unordered_map<VoxelIndex, SourceBlockInfo, VoxelIndexHash> m_map;
	VoxelIndex m_lo, m_hi;
	int64_t m_nx{0}, m_ny{0};
	std::vector<const SourceBlockInfo*> m_dense;
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

/** Where the box [lo, hi] (world, axis-aligned) lies relative to the corrected view cone,
 * exactly for `Inside` (the cone is convex, so all 8 corners inside means the box is) and
 * conservatively for `Outside` (all corners behind one face of the pyramid, or the box farther
 * than the range from the camera centre). */
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
	// 5 faces through the camera centre: z > 0 and the 4 side planes (camera frame).
	int behind[5] = {0, 0, 0, 0, 0};
	for (int i = 0; i < 8; ++i)
	{
		const auto p = k.worldToCamNew({(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
		if (!(p.z > 0)) ++behind[0];
		for (int j = 0; j < 4; ++j)
		{
			const auto& n = k.planes[j];
			if (n[0] * p.x + n[1] * p.y + n[2] * p.z < 0) ++behind[j + 1];
		}
	}
	for (int j = 0; j < 5; ++j)
	{
		if (behind[j] == 8) return ConeOverlap::Outside;
		inside = inside && behind[j] == 0;
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
					}
					h.cumCount.back() = static_cast<uint32_t>(i + 1);
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

	const unsigned nt = detail::resolveThreads(opts.threads);
	std::vector<MorphingStats> partial(nt);
	const double zMin = opts.minWeightDistance, pw = opts.weightExponent, invRes = 1.0 / res;
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
		// slot keeps the bounding box (voxel indices) of the block's known voxels in the travel
		// window of k (with the slack of readableRegion); block = nullptr when there are none, as
		// then no voxel of the block can count.
		struct Slot
		{
			VoxelIndex key;
			const VoxelBlock* block;
			VoxelIndex lo, hi;
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
						const VoxelIndex f = VoxelBlockGrid::firstVoxelOf(b);
						sl.lo = {INT32_MAX, INT32_MAX, INT32_MAX}, sl.hi = {INT32_MIN, INT32_MIN, INT32_MIN};
						for (std::size_t v = i; v < j; ++v)
						{
							const auto& bx = h.box[v];
							sl.lo = {std::min(sl.lo.x, f.x + bx[0]), std::min(sl.lo.y, f.y + bx[1]), std::min(sl.lo.z, f.z + bx[2])};
							sl.hi = {std::max(sl.hi.x, f.x + bx[3]), std::max(sl.hi.y, f.y + bx[4]), std::max(sl.hi.z, f.z + bx[5])};
						}
					}
				}
			}
			return sl;
		};
		// Known source voxels a lookup through keyframe k from the block whose voxel centres
		// span [clo, chi] may read (in the travel window of k when the window is on), and their
		// bounding box [vlo, vhi] (voxel indices): the earlier positions of those centres lie in
		// the AABB of the 8 mapped corners (the map is affine), and lookups read at most one
		// voxel beyond (one more of margin for rounding). A count of 0 means no lookup through k
		// can succeed, so dropping k changes no result; a lookup whose corners all miss the box
		// cannot succeed either.
		struct Region
		{
			std::size_t count{0};
			VoxelIndex lo{INT32_MAX, INT32_MAX, INT32_MAX}, hi{INT32_MIN, INT32_MIN, INT32_MIN};
		};
		auto readableRegion = [&](const PreparedKeyframe& k, const mrpt::math::TPoint3D& clo,
								  const mrpt::math::TPoint3D& chi) {
			double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
			for (int c = 0; c < 8; ++c)
			{
				const auto q = k.newToOld({(c & 1) ? chi.x : clo.x, (c & 2) ? chi.y : clo.y,
					(c & 4) ? chi.z : clo.z});
				const double qq[3] = {q.x, q.y, q.z};
				for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], qq[a]), hi[a] = std::max(hi[a], qq[a]);
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
			const mrpt::math::TPoint3D clo = out.centreOf(first),
									   chi = out.centreOf({first.x + kS - 1, first.y + kS - 1, first.z + kS - 1});
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
				// Readable box with one voxel (plus rounding) of margin, in voxel-centre units.
				const double boxLo[3] = {nk.lo.x - 1.001, nk.lo.y - 1.001, nk.lo.z - 1.001};
				const double boxHi[3] = {nk.hi.x + 1.001, nk.hi.y + 1.001, nk.hi.z + 1.001};
				// Per-voxel steps along a row of the clipped quantities below, and their inverses.
				double planeStep[4], invStep[8];
				for (int j = 0; j < 4; ++j)
				{
					const auto& n = k.planes[j];
					planeStep[j] = n[0] * ca[0][0] + n[1] * ca[0][1] + n[2] * ca[0][2];
				}
				{
					const double steps[8] = {g[0][0], g[0][1], g[0][2], ca[0][2], planeStep[0], planeStep[1],
						planeStep[2], planeStep[3]};
					for (int j = 0; j < 8; ++j) invStep[j] = steps[j] != 0 ? 1.0 / steps[j] : 0.0;
				}
				for (int lz = 0; lz < kS; ++lz)
					for (int ly = 0; ly < kS; ++ly)
					{
						// Along a row (lx = 0..7) every test below but the range is affine in lx:
						// clip the row to where all hold (widened by 1e-6 so that only voxels that
						// fail the exact per-voxel tests are left out).
						double lxLo = 0, lxHi = kS - 1;
						// f0 + lx * df >= bound (atLeast) or <= bound; inv = 1 / df (0 when df = 0).
						auto clip = [&](double f0, double df, double inv, double bound, bool atLeast) {
							if (!atLeast) f0 = -f0, df = -df, inv = -inv, bound = -bound;
							if (df > 0) lxLo = std::max(lxLo, (bound - f0) * inv - 1e-6);
							else if (df < 0) lxHi = std::min(lxHi, (bound - f0) * inv + 1e-6);
							else if (f0 < bound - 1e-9) lxHi = -1;
						};
						const double r0[3] = {qa[0] + ly * g[1][0] + lz * g[2][0], qa[1] + ly * g[1][1] + lz * g[2][1],
							qa[2] + ly * g[1][2] + lz * g[2][2]};
						for (int a = 0; a < 3; ++a)
						{
							clip(r0[a], g[0][a], invStep[a], boxLo[a], true);
							clip(r0[a], g[0][a], invStep[a], boxHi[a], false);
						}
						if (nk.partial)
						{
							const double p0[3] = {pc0.x + ly * ca[1][0] + lz * ca[2][0],
								pc0.y + ly * ca[1][1] + lz * ca[2][1], pc0.z + ly * ca[1][2] + lz * ca[2][2]};
							clip(p0[2], ca[0][2], invStep[3], 0.0, true);
							for (int j = 0; j < 4; ++j)
							{
								const auto& n = k.planes[j];
								clip(n[0] * p0[0] + n[1] * p0[1] + n[2] * p0[2], planeStep[j], invStep[4 + j], 0.0, true);
							}
						}
						if (lxHi < lxLo) continue;
						const int lxBegin = std::max(0, static_cast<int>(std::ceil(lxLo)));
						const int lxEnd = std::min(kS - 1, static_cast<int>(std::floor(lxHi)));
						for (int lx = lxBegin; lx <= lxEnd; ++lx)
						{
							const int li = VoxelBlock::linear(lx, ly, lz);
							const mrpt::math::TPoint3D X = out.centreOf({first.x + lx, first.y + ly, first.z + lz});
							const double dz2 = (X.x - k.centreNew.x) * (X.x - k.centreNew.x) +
								(X.y - k.centreNew.y) * (X.y - k.centreNew.y) +
								(X.z - k.centreNew.z) * (X.z - k.centreNew.z);
							if (nk.partial)
							{
								// Inside the corrected cone: in front, within range, inside the 4 side
								// planes of the image pyramid (the pixel test without division).
								const double px = pc0.x + lx * ca[0][0] + ly * ca[1][0] + lz * ca[2][0];
								const double py = pc0.y + lx * ca[0][1] + ly * ca[1][1] + lz * ca[2][1];
								const double pz = pc0.z + lx * ca[0][2] + ly * ca[1][2] + lz * ca[2][2];
								if (!(pz > 0) || dz2 > maxRange2) continue;
								bool in = true;
								for (const auto& n : k.planes) in = in && n[0] * px + n[1] * py + n[2] * pz >= 0;
								if (!in) continue;
							}
							// Earlier position in voxel units. A lookup reads voxels within one of it: none
							// is usable when it is more than one voxel outside the readable box.
							const double rx = qa[0] + lx * g[0][0] + ly * g[1][0] + lz * g[2][0];
							const double ry = qa[1] + lx * g[0][1] + ly * g[1][1] + lz * g[2][1];
							const double rz = qa[2] + lx * g[0][2] + ly * g[1][2] + lz * g[2][2];
							if (rx < boxLo[0] || ry < boxLo[1] || rz < boxLo[2] || rx > boxHi[0] ||
								ry > boxHi[1] || rz > boxHi[2])
								continue;
							++ps.attemptedLookups;
							// Positions within 1e-6 voxel of a centre snap to it, so that an identity or
							// whole-voxel correction reads exactly one voxel (rounding of the composed pose).
							// r = nearest centre; trilinear corner x0 = floor(position), f its fraction.
							int32_t x0 = floorToInt(rx + 0.5), y0 = floorToInt(ry + 0.5), z0 = floorToInt(rz + 0.5);
							double fx = 0, fy = 0, fz = 0;
							if (trilinear)
							{
								auto corner = [](double q, int32_t& i, double& f) {
									const double d = q - i;
									if (std::abs(d) < 1e-6) return;  // snapped: f = 0
									i -= d < 0;
									f = q - i;
								};
								corner(rx, x0, fx), corner(ry, y0, fy), corner(rz, z0, fz);
							}
							const double wx[2] = {1 - fx, fx}, wy[2] = {1 - fy, fy}, wz[2] = {1 - fz, fz};
							double cw = 0, cl = 0, cbest = -1;
							float ctravel = 0;
							// All 8 corners in one source block (7 times in 8 per axis): one block lookup,
							// corners at fixed offsets, no branches (a corner that does not count adds
							// exactly 0, so the sums equal those of the general path below).
							constexpr int m = kS - 1;
							if ((x0 & m) != m && (y0 & m) != m && (z0 & m) != m)
							{
								const Slot& sl = sourceSlot(VoxelBlockGrid::blockOf(VoxelIndex{x0, y0, z0}));
								if (!sl.block || x0 + 1 < sl.lo.x || y0 + 1 < sl.lo.y || z0 + 1 < sl.lo.z ||
									x0 > sl.hi.x || y0 > sl.hi.y || z0 > sl.hi.z)
									continue;  // no corner can count
								const Voxel* v0 = &sl.block->voxels[VoxelBlockGrid::localLinear({x0, y0, z0})];
								constexpr int off[8] = {0, 1, kS, kS + 1, kS * kS, kS * kS + 1, kS * kS + kS, kS * kS + kS + 1};
								for (int c = 0; c < 8; ++c)
								{
									const Voxel& src = v0[off[c]];
									const double tc = wx[c & 1] * wy[(c >> 1) & 1] * wz[c >> 2];
									const bool ok = (tc > 0) & src.isKnown() &
										(!window | (std::abs(double(src.travelled) - tw) <= opts.travelWindow));
									const double tk = ok ? tc : 0.0;
									cw += tk;
									cl += tk * double(src.logOdds);
									const bool better = ok & (tc > cbest);
									cbest = better ? tc : cbest;
									ctravel = better ? src.travelled : ctravel;
								}
							}
							else
								for (int c = 0; c < 8; ++c)
								{
									const double tc = wx[c & 1] * wy[(c >> 1) & 1] * wz[c >> 2];
									if (tc <= 0) continue;
									const VoxelIndex sv{x0 + (c & 1), y0 + ((c >> 1) & 1), z0 + ((c >> 2) & 1)};
									const Slot& sl = sourceSlot(VoxelBlockGrid::blockOf(sv));
									if (!sl.block || sv.x < sl.lo.x || sv.y < sl.lo.y || sv.z < sl.lo.z ||
										sv.x > sl.hi.x || sv.y > sl.hi.y || sv.z > sl.hi.z)
										continue;
									const Voxel& src = sl.block->voxels[VoxelBlockGrid::localLinear(sv)];
									if (!src.isKnown()) continue;
									if (window && std::abs(double(src.travelled) - tw) > opts.travelWindow) continue;
									cw += tc;
									cl += tc * double(src.logOdds);
									if (tc > cbest) cbest = tc, ctravel = src.travelled;
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

	// 3. Voxels no cone gave a value keep their own, moved with their last updater's correction.
	if (opts.keepVoxelsOutsideCones)
	{
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
