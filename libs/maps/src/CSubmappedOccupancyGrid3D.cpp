/** \file CSubmappedOccupancyGrid3D.cpp
 * Construction, options, MRPT map definition, submap queries. Integration is in _insert.cpp,
 * morphing in _morph.cpp, serialization / exports / visualization in _io.cpp.
 */
#include "detail/OptionValues.h"

#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <mrpt/config/CConfigFileBase.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <tuple>

using namespace keygrid;

IMPLEMENTS_SERIALIZABLE(CSubmappedOccupancyGrid3D, mrpt::maps::CMetricMap, keygrid)

MAP_DEFINITION_REGISTER(
	"keygrid::CSubmappedOccupancyGrid3D,submappedOccupancyGrid3D",
	keygrid::CSubmappedOccupancyGrid3D)

// ---------------------------------------------------------------- map definition (INI)
CSubmappedOccupancyGrid3D::TMapDefinition::TMapDefinition() = default;

core::OptionFields CSubmappedOccupancyGrid3D::TMapDefinition::creationFields()
{
	core::OptionFields f;
	f.add("resolution", resolution, "voxel edge [m]", core::OptionRule::inRange(kMinResolution, kMaxResolution));
	return f;
}

void CSubmappedOccupancyGrid3D::TMapDefinition::loadFromConfigFile_map_specific(
	const mrpt::config::CConfigFileBase& source, const std::string& prefix)
{
	const std::string sCreation = prefix + "_creationOpts";
	auto creation = creationFields();
	creation.read(source, sCreation);
	creation.validate(sCreation);
	insertionOpts.loadFromConfigFile(source, prefix + "_insertOpts");
	morphingOpts.loadFromConfigFile(source, prefix + "_insertOpts");
	likelihoodOpts.loadFromConfigFile(source, prefix + "_likelihoodOpts");
}

void CSubmappedOccupancyGrid3D::TMapDefinition::dumpToTextStream_map_specific(
	std::ostream& out) const
{
	out << "resolution = " << resolution << " m\n";
	insertionOpts.dumpToTextStream(out);
	likelihoodOpts.dumpToTextStream(out);
}

mrpt::maps::CMetricMap* CSubmappedOccupancyGrid3D::internal_CreateFromMapDefinition(
	const mrpt::maps::TMetricMapInitializer& _def)
{
	const auto& def = dynamic_cast<const CSubmappedOccupancyGrid3D::TMapDefinition&>(_def);
	auto* m = new CSubmappedOccupancyGrid3D(def.resolution);
	m->insertionOptions = def.insertionOpts;
	m->morphingOptions = def.morphingOpts;
	m->likelihoodOptions = def.likelihoodOpts;
	return m;
}

// ---------------------------------------------------------------- options
core::OptionFields CSubmappedOccupancyGrid3D::TInsertionOptions::fields()
{
	core::OptionFields f;
	f.append(integration.fields());
	f.append(conflict.fields());
	f.addCustom("storeKeyframeDepth", detail::flagValue(storeKeyframeDepth), "keep each keyframe's depth image (1.2 MB at 640x480) to re-integrate it at corrected poses");
	f.addCustom("observationsAreKeyframes", detail::flagValue(observationsAreKeyframes), "insertObservation(): record every observation as a keyframe (false: only update the grid)");
	return f;
}

void CSubmappedOccupancyGrid3D::TInsertionOptions::validate(const std::string& s) const
{
	integration.validate(s);
	conflict.validate(s);  // the two flags take any value
}

core::OptionFields CSubmappedOccupancyGrid3D::TLikelihoodOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("decimation", decimation, "use every n-th depth pixel in rows and columns", R::atLeast(1));
	f.add("maxRange", maxRange, "pixels farther than this from the camera centre are left out [m]", R::positive());
	f.add("minProbability", minProbability, "floor of each pixel's occupancy probability (unknown voxels: 0.5)", R::between(0, 0.5));
	return f;
}

// ---------------------------------------------------------------- basics
CSubmappedOccupancyGrid3D::CSubmappedOccupancyGrid3D(double resolution)
{
	setResolution(resolution);
}

void CSubmappedOccupancyGrid3D::setResolution(double resolution)
{
	if (!(resolution >= kMinResolution && resolution <= kMaxResolution))
		throw std::invalid_argument(
			"CSubmappedOccupancyGrid3D: resolution = " + std::to_string(resolution) + " (must be in [" + std::to_string(kMinResolution) +
			", " + std::to_string(kMaxResolution) + "] m)");
	m_resolution = resolution;
	internal_clear();
}

void CSubmappedOccupancyGrid3D::internal_clear()
{
	m_submaps.assign(1, Submap(m_resolution));
	m_active = 0;
	m_keyframes.clear();
	m_lastKeyframe.reset();
	m_modeMachine = MappingModeMachine(insertionOptions.conflict);
	m_lastObsCamPose.reset();
	m_obsTravelled = 0;
	m_nextObsKeyframeId = 0;
}

bool CSubmappedOccupancyGrid3D::isEmpty() const
{
	for (const auto& s : m_submaps)
		if (s.grid.numBlocks() > 0) return false;
	return true;
}

std::string CSubmappedOccupancyGrid3D::asString() const
{
	std::size_t blocks = 0;
	for (const auto& s : m_submaps) blocks += s.grid.numBlocks();
	std::ostringstream o;
	o << "keygrid::CSubmappedOccupancyGrid3D: resolution " << m_resolution << " m, "
	  << m_submaps.size() << " submap(s), " << m_keyframes.size() << " keyframe(s), " << blocks
	  << " blocks of 8^3 voxels, mode " << toString(mode());
	return o.str();
}

DepthFrameIntegrator& CSubmappedOccupancyGrid3D::integrator()
{
	if (!m_integrator.ptr)
		m_integrator.ptr = std::make_unique<DepthFrameIntegrator>(insertionOptions.integration);
	else
		m_integrator.ptr->setOptions(insertionOptions.integration);
	return *m_integrator.ptr;
}

std::optional<float> CSubmappedOccupancyGrid3D::logOddsAt(const mrpt::math::TPoint3D& p) const
{
	for (auto it = m_submaps.rbegin(); it != m_submaps.rend(); ++it)
	{
		const Voxel* v = it->grid.find(it->grid.voxelOf(p));
		if (v && v->isKnown()) return v->logOdds;
	}
	return std::nullopt;
}

VoxelBlockGrid CSubmappedOccupancyGrid3D::fusedGrid() const
{
	if (m_submaps.size() == 1) return m_submaps.front().grid;
	VoxelBlockGrid out(m_resolution);
	// Oldest first, so newer submaps overwrite where both know a voxel.
	for (const auto& s : m_submaps)
		s.grid.forEachKnown([&](const VoxelIndex& vi, const Voxel& v) { out.at(vi) = v; });
	return out;
}

std::vector<mrpt::math::TPoint3D> CSubmappedOccupancyGrid3D::occupiedVoxelCentres() const
{
	std::vector<mrpt::math::TPoint3D> pts;
	const VoxelBlockGrid g = fusedGrid();
	g.forEachKnown([&](const VoxelIndex& vi, const Voxel& v) {
		if (v.logOdds > 0.0f) pts.push_back(g.centreOf(vi));
	});
	// A fixed order (the voxels' hash order depends on the map's history, e.g. a map restored
	// from its serialization lists them differently): the same map gives the same output.
	std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); });
	return pts;
}

std::size_t CSubmappedOccupancyGrid3D::memoryBytes() const
{
	std::size_t b = 0;
	for (const auto& s : m_submaps) b += s.grid.memoryBytes();
	for (const auto& kv : m_keyframes)
		b += kv.second.depth.total() * kv.second.depth.elemSize() + kv.second.points_cam.size() * sizeof(mrpt::math::TPoint3Df);
	return b;
}
