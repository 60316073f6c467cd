/** \file CHOCPointsMap.cpp
 * CHOCPointsMap: MRPT map definition, options, point bookkeeping, depth-scan insertion and
 * likelihood. Serialization, PLY and visualization are in CHOCPointsMap_io.cpp.
 */
#include "detail/DepthOfScan.h"
#include "detail/MapDefinitionSections.h"

#include <keygrid/maps/CHOCPointsMap.h>
#include <mrpt/config/CConfigFileBase.h>

#include <algorithm>
#include <cmath>
#include <sstream>

using namespace keygrid;

IMPLEMENTS_SERIALIZABLE(CHOCPointsMap, mrpt::maps::CMetricMap, keygrid)

MAP_DEFINITION_REGISTER("keygrid::CHOCPointsMap,hocPointsMap", keygrid::CHOCPointsMap)

// ---------------------------------------------------------------- map definition (INI)
CHOCPointsMap::TMapDefinition::TMapDefinition() = default;

void CHOCPointsMap::TMapDefinition::loadFromConfigFile_map_specific(
	const mrpt::config::CConfigFileBase& source, const std::string& prefix)
{
	detail::loadMapSections(source, prefix, hocOpts, insertionOpts, likelihoodOpts);
}

void CHOCPointsMap::TMapDefinition::dumpToTextStream_map_specific(std::ostream& out) const
{
	detail::dumpMapSections(out, hocOpts, insertionOpts, likelihoodOpts);
}

mrpt::maps::CMetricMap* CHOCPointsMap::internal_CreateFromMapDefinition(const mrpt::maps::TMetricMapInitializer& _def)
{
	const auto& def = dynamic_cast<const CHOCPointsMap::TMapDefinition&>(_def);
	auto* m = new CHOCPointsMap(def.hocOpts);
	m->insertionOptions = def.insertionOpts;
	m->likelihoodOptions = def.likelihoodOpts;
	return m;
}

// ---------------------------------------------------------------- options
core::OptionFields CHOCPointsMap::TInsertionOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("decimation", decimation, "use every n-th depth pixel (rows and columns)", R::atLeast(1));
	f.add("point_spacing", pointSpacing, "[m] new points only in voxels of this size without points", R::positive());
	f.add("prune", prune, "remove points below prune_threshold after each insertion");
	return f;
}

core::OptionFields CHOCPointsMap::TLikelihoodOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("decimation", decimation, "use every n-th depth pixel", R::atLeast(1));
	f.add("sigma", sigma, "[m] std. dev. of the point distance", R::positive());
	f.add("outlier_probability", outlierProbability, "floor of one pixel's likelihood", R::between(0, 1));
	return f;
}

// ---------------------------------------------------------------- points
const maps::HocGeometry& CHOCPointsMap::geometry() const
{
	auto& g = m_geometry.ptr;
	if (!g || g->radii() != hocOptions.radii || g->subdivisions() != hocOptions.subdivisions)
		g = std::make_shared<maps::HocGeometry>(hocOptions.radii, hocOptions.subdivisions);
	return *g;
}

void CHOCPointsMap::setPoints(std::vector<Point> pts)
{
	const auto nb = static_cast<std::size_t>(geometry().numBins());
	for (const auto& p : pts)
		if (p.hoc.touched() && p.hoc.counts().size() != nb)
			throw std::invalid_argument(
				"CHOCPointsMap::setPoints: point " + std::to_string(p.id) + " has " + std::to_string(p.hoc.counts().size()) +
				" bins, the map's geometry has " + std::to_string(nb));
	m_points = std::move(pts);
	m_nextId = 0;
	for (const auto& p : m_points) m_nextId = std::max(m_nextId, p.id + 1);
}

std::size_t CHOCPointsMap::prune()
{
	const auto before = m_points.size();
	m_points.erase(
		std::remove_if(m_points.begin(), m_points.end(), [&](const Point& p) { return hocOptions.weight(p.hoc.maxCount()) < hocOptions.pruneThreshold; }),
		m_points.end());
	return before - m_points.size();
}

void CHOCPointsMap::internal_clear()
{
	m_points.clear();
	m_nextId = 0;
}

std::string CHOCPointsMap::asString() const
{
	std::ostringstream o;
	o << "CHOCPointsMap: " << m_points.size() << " points, " << geometry().numShells() << " shells x " << geometry().numFaces() << " faces";
	return o.str();
}

// ---------------------------------------------------------------- depth scans
namespace
{
struct VoxelKey
{
	std::int64_t x, y, z;
	bool operator==(const VoxelKey& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct VoxelKeyHash
{
	std::size_t operator()(const VoxelKey& k) const
	{
		return static_cast<std::size_t>(k.x * 73856093LL ^ k.y * 19349663LL ^ k.z * 83492791LL);
	}
};
VoxelKey voxelOf(const mrpt::math::TPoint3D& p, double s)
{
	return {static_cast<std::int64_t>(std::floor(p.x / s)), static_cast<std::int64_t>(std::floor(p.y / s)), static_cast<std::int64_t>(std::floor(p.z / s))};
}
using VoxelIndex = std::unordered_multimap<VoxelKey, std::size_t, VoxelKeyHash>;
VoxelIndex indexPoints(const std::vector<CHOCPointsMap::Point>& pts, double s)
{
	VoxelIndex idx;
	idx.reserve(pts.size());
	for (std::size_t i = 0; i < pts.size(); i++) idx.emplace(voxelOf(pts[i].p, s), i);
	return idx;
}
}  // namespace

bool CHOCPointsMap::insertDepthScan(const mrpt::obs::CObservation3DRangeScan& scan, const mrpt::poses::CPose3D& T_world_cam)
{
	cv::Mat depth;
	core::RgbdCamera cam;
	if (!detail::depthOfScan(scan, depth, cam)) return false;
	const mrpt::poses::CPose3D T_cam_world = -T_world_cam;
	const Eigen::Vector3d centre(T_world_cam.x(), T_world_cam.y(), T_world_cam.z());
	const auto& geom = geometry();
	const int nb = geom.numBins();
	const auto& o = hocOptions;

	// 1. Existing points: agreement (+1), seen through (-1), occluded or unmeasured (nothing).
	for (auto& pt : m_points)
	{
		double x, y, z;
		T_cam_world.composePoint(pt.p.x, pt.p.y, pt.p.z, x, y, z);
		if (z < o.visibleDepthMin || z > o.visibleDepthMax) continue;
		const int u = static_cast<int>(std::lround(cam.fx * x / z + cam.cx)), v = static_cast<int>(std::lround(cam.fy * y / z + cam.cy));
		if (u < 0 || v < 0 || u >= depth.cols || v >= depth.rows) continue;
		const float d = depth.at<float>(v, u);
		const bool measured = d > 0 && std::isfinite(d);
		const double tol = o.occlusionToleranceAbs + o.occlusionToleranceRel * z;
		const int b = geom.bin({pt.p.x, pt.p.y, pt.p.z}, centre);
		if (b < 0) continue;
		if (measured && std::abs(d - z) <= tol) pt.hoc.add(b, +1, o.countLimit, nb);
		else if (!measured || d > z + tol)  // seen through, or no return where it should be
			pt.hoc.add(b, -1, o.countLimit, nb);
	}
	// 2. New points where no point exists yet.
	auto idx = indexPoints(m_points, insertionOptions.pointSpacing);
	const int step = insertionOptions.decimation;
	const core::PinholeIntrinsics K = cam.pinhole();
	for (int r = step / 2; r < depth.rows; r += step)
		for (int c = step / 2; c < depth.cols; c += step)
		{
			const float d = depth.at<float>(r, c);
			if (!(d > 0) || !std::isfinite(d) || d < o.visibleDepthMin || d > o.visibleDepthMax) continue;
			const Eigen::Vector3d p_cam = K.backProject(c, r, d);
			Point pt;
			T_world_cam.composePoint(p_cam.x(), p_cam.y(), p_cam.z(), pt.p.x, pt.p.y, pt.p.z);
			const VoxelKey k = voxelOf(pt.p, insertionOptions.pointSpacing);
			if (idx.count(k)) continue;
			pt.id = m_nextId++;
			const int b = geom.bin({pt.p.x, pt.p.y, pt.p.z}, centre);
			if (b >= 0) pt.hoc.add(b, o.initialCount, o.countLimit, nb);
			idx.emplace(k, m_points.size());
			m_points.push_back(std::move(pt));
		}
	if (insertionOptions.prune) prune();
	return true;
}

double CHOCPointsMap::depthScanLikelihood(const mrpt::obs::CObservation3DRangeScan& scan, const mrpt::poses::CPose3D& T_world_cam) const
{
	cv::Mat depth;
	core::RgbdCamera cam;
	if (!detail::depthOfScan(scan, depth, cam) || m_points.empty()) return 0;
	const double s = std::max(insertionOptions.pointSpacing, 3 * likelihoodOptions.sigma);
	const auto idx = indexPoints(m_points, s);
	const double inv2s2 = 1.0 / (2 * likelihoodOptions.sigma * likelihoodOptions.sigma);
	double logLik = 0;
	const int step = likelihoodOptions.decimation;
	const core::PinholeIntrinsics K = cam.pinhole();
	for (int r = step / 2; r < depth.rows; r += step)
		for (int c = step / 2; c < depth.cols; c += step)
		{
			const float d = depth.at<float>(r, c);
			if (!(d > 0) || !std::isfinite(d)) continue;
			const Eigen::Vector3d p_cam = K.backProject(c, r, d);
			mrpt::math::TPoint3D p;
			T_world_cam.composePoint(p_cam.x(), p_cam.y(), p_cam.z(), p.x, p.y, p.z);
			const VoxelKey k = voxelOf(p, s);
			double best = 1e300;
			for (int dx = -1; dx <= 1; dx++)
				for (int dy = -1; dy <= 1; dy++)
					for (int dz = -1; dz <= 1; dz++)
					{
						auto range = idx.equal_range({k.x + dx, k.y + dy, k.z + dz});
						for (auto it = range.first; it != range.second; ++it)
						{
							const auto& q = m_points[it->second].p;
							best = std::min(best, (q.x - p.x) * (q.x - p.x) + (q.y - p.y) * (q.y - p.y) + (q.z - p.z) * (q.z - p.z));
						}
					}
			const double po = likelihoodOptions.outlierProbability;
			logLik += std::log(po + (1 - po) * (best < 1e299 ? std::exp(-best * inv2s2) : 0.0));
		}
	return logLik;
}
