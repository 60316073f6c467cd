#include <keygrid/core/JsonNumber.h>
#include <keygrid/eval/VoxelMapMetrics.h>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <unordered_set>

namespace keygrid::eval
{
namespace
{
/** 21 bits per axis (indices within +-2^20 voxels). */
uint64_t key(const VoxelIndex& v)
{
	constexpr int64_t kOffset = 1 << 20;
	constexpr uint64_t kMask = (uint64_t(1) << 21) - 1;
	return (uint64_t(v[0] + kOffset) & kMask) | ((uint64_t(v[1] + kOffset) & kMask) << 21) |
		   ((uint64_t(v[2] + kOffset) & kMask) << 42);
}

VoxelIndex indexIn(const Eigen::Vector3d& p, double res, const Eigen::Vector3d& origin)
{
	const Eigen::Vector3d q = (p - origin) / res;
	return {static_cast<int32_t>(std::floor(q.x())), static_cast<int32_t>(std::floor(q.y())), static_cast<int32_t>(std::floor(q.z()))};
}

/** Lattice offsets whose length is at most `radius` voxels. */
std::vector<VoxelIndex> offsetsWithin(double radius)
{
	const int r = static_cast<int>(std::floor(radius + 1e-9));
	std::vector<VoxelIndex> out;
	for (int z = -r; z <= r; z++)
		for (int y = -r; y <= r; y++)
			for (int x = -r; x <= r; x++)
				if (x * x + y * y + z * z <= radius * radius + 1e-9) out.push_back({x, y, z});
	return out;
}

VoxelIndex plus(const VoxelIndex& a, const VoxelIndex& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }

double ratio(std::size_t a, std::size_t b) { return b ? double(a) / double(b) : 0.0; }

}  // namespace

VoxelTruth::VoxelTruth(double resolution, const Eigen::Vector3d& origin, const std::vector<VoxelIndex>& occupied)
	: m_res(resolution), m_origin(origin)
{
	if (!(resolution > 0)) throw std::invalid_argument("VoxelTruth: resolution must be > 0 m (got " + std::to_string(resolution) + ")");
	m_voxels.reserve(occupied.size());
	for (const auto& v : occupied)
		if (m_lookup.emplace(key(v), m_voxels.size()).second) m_voxels.push_back(v);
	m_seen.assign(m_voxels.size(), 0);
}

VoxelIndex VoxelTruth::indexOf(const Eigen::Vector3d& p_world) const { return indexIn(p_world, m_res, m_origin); }

Eigen::Vector3d VoxelTruth::centre(const VoxelIndex& v) const
{
	return m_origin + m_res * Eigen::Vector3d(v[0] + 0.5, v[1] + 0.5, v[2] + 0.5);
}

long VoxelTruth::find(const VoxelIndex& v) const
{
	const auto it = m_lookup.find(key(v));
	return it == m_lookup.end() ? -1 : static_cast<long>(it->second);
}

int VoxelTruth::markSeen(const Eigen::Vector3d& p_world)
{
	constexpr double kFace = 1e-3;  // [m]: a point this close to a voxel face lies on it
	const VoxelIndex base = indexOf(p_world);
	// The axes along which p lies within kFace of a face, and the neighbour across it.
	std::array<int, 3> across{0, 0, 0};
	for (int a = 0; a < 3; a++)
	{
		const double f = (p_world[a] - m_origin[a]) / m_res - base[a];
		if (f * m_res < kFace) across[a] = -1;
		else if ((1 - f) * m_res < kFace) across[a] = 1;
	}
	int marked = 0;
	for (int m = 0; m < 8; m++)
	{
		VoxelIndex v = base;
		bool skip = false;
		for (int a = 0; a < 3; a++)
			if (m & (1 << a))
			{
				if (!across[a]) skip = true;
				v[a] += across[a];
			}
		if (skip) continue;
		const long i = find(v);
		if (i < 0) continue;
		m_seen[static_cast<std::size_t>(i)] = 1;
		m_anySeen = true;
		marked++;
	}
	return marked;
}

bool VoxelMapMetricsOptions::isValid(std::string* error) const
{
	std::string why;
	if (!(matchTolerance >= 0)) why = "matchTolerance must be >= 0 m (got " + std::to_string(matchTolerance) + ")";
	if (error) *error = why;
	return why.empty();
}

VoxelMapMetrics evaluateVoxelMap(
	const VoxelMapEstimate& est, const Similarity3& T_gt_map, const VoxelTruth& truth, const VoxelMapMetricsOptions& opts)
{
	std::string why;
	if (!opts.isValid(&why)) throw std::invalid_argument("evaluateVoxelMap: " + why);
	if (!(est.resolution > 0))
		throw std::invalid_argument("evaluateVoxelMap: map resolution must be > 0 m (got " + std::to_string(est.resolution) + ")");
	if (!(T_gt_map.s > 0)) throw std::invalid_argument("evaluateVoxelMap: the alignment's scale must be > 0");
	const auto offsets = offsetsWithin(opts.matchTolerance / truth.resolution());
	const Eigen::Vector3d half = Eigen::Vector3d::Constant(0.5);

	VoxelMapMetrics m;
	// Occupied map voxels, each at the true voxel its centre falls in.
	std::unordered_set<uint64_t> occupiedOnTruth, occupiedInMap, freeInMap;
	for (const auto& e : est.occupied)
	{
		if (!occupiedInMap.insert(key(e)).second) continue;
		const Eigen::Vector3d c_map = est.resolution * (Eigen::Vector3d(e[0], e[1], e[2]) + half);
		const VoxelIndex g = truth.indexOf(T_gt_map.apply(c_map));
		occupiedOnTruth.insert(key(g));
		m.estOccupied++;
		for (const auto& d : offsets)
			if (truth.find(plus(g, d)) >= 0)
			{
				m.estOccupiedMatched++;
				break;
			}
	}
	for (const auto& e : est.free)
		if (!occupiedInMap.count(key(e)) && freeInMap.insert(key(e)).second) m.estFree++;
	m.precision = ratio(m.estOccupiedMatched, m.estOccupied);

	// True voxels: matched by a map occupied voxel, or lying in a map free voxel.
	const Eigen::Matrix3d R_map_gt = T_gt_map.R.transpose();
	const auto& gt = truth.occupied();
	for (std::size_t i = 0; i < gt.size(); i++)
	{
		bool matched = false;
		for (const auto& d : offsets)
			if (occupiedOnTruth.count(key(plus(gt[i], d))))
			{
				matched = true;
				break;
			}
		const Eigen::Vector3d c_map = R_map_gt * (truth.centre(gt[i]) - T_gt_map.t) / T_gt_map.s;
		const bool calledFree = freeInMap.count(key(indexIn(c_map, est.resolution, Eigen::Vector3d::Zero()))) > 0;
		m.gtOccupied++;
		m.gtOccupiedMatched += matched;
		if (truth.seen(i))
		{
			m.gtSeen++;
			m.gtSeenMatched += matched;
		}
		m.gtCalledFree += calledFree;
		m.hazardVoxels += calledFree && !matched;
	}
	m.recall = ratio(m.gtOccupiedMatched, m.gtOccupied);
	m.seenRecall = ratio(m.gtSeenMatched, m.gtSeen);
	return m;
}

std::string VoxelMapMetrics::toText() const
{
	char b[1024];
	std::snprintf(
		b, sizeof(b),
		"  occupied voxels %zu (free %zu): precision %.4f (%zu within the tolerance of a true voxel)\n"
		"  recall, true voxels seen %.4f (%zu of %zu); all true voxels %.4f (%zu of %zu)\n"
		"  true voxels called free %zu; hazard voxels (called free, no map voxel within the tolerance) %zu\n",
		estOccupied, estFree, precision, estOccupiedMatched, seenRecall, gtSeenMatched, gtSeen, recall, gtOccupiedMatched,
		gtOccupied, gtCalledFree, hazardVoxels);
	return b;
}

std::string VoxelMapMetrics::jsonFields(const std::string& prefix) const
{
	std::ostringstream o;
	const auto field = [&](const char* name, const std::string& v, bool last = false) {
		o << "  \"" << prefix << name << "\": " << v << (last ? "" : ",\n");
	};
	field("occupied_voxels", std::to_string(estOccupied));
	field("occupied_matched", std::to_string(estOccupiedMatched));
	field("free_voxels", std::to_string(estFree));
	field("precision", core::jsonNumber(precision, 6));
	field("true_voxels", std::to_string(gtOccupied));
	field("recall", core::jsonNumber(recall, 6));
	field("true_voxels_seen", std::to_string(gtSeen));
	field("recall_seen", core::jsonNumber(seenRecall, 6));
	field("true_called_free", std::to_string(gtCalledFree));
	field("hazard_voxels", std::to_string(hazardVoxels), true);
	return o.str();
}

}  // namespace keygrid::eval
