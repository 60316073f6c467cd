/** \file CSubmappedOccupancyGrid3D.cpp
 * Construction, options, MRPT map definition, submap queries. Integration is in _insert.cpp,
 * morphing in _morph.cpp, serialization / exports / visualization in _io.cpp.
 */
#include "detail/Grid3DConfig.h"

#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>

#include <algorithm>
#include <tuple>
#include <mrpt/config/CConfigFileBase.h>

#include <cmath>
#include <sstream>

using namespace keygrid;

IMPLEMENTS_SERIALIZABLE(CSubmappedOccupancyGrid3D, mrpt::maps::CMetricMap, keygrid)

MAP_DEFINITION_REGISTER(
	"keygrid::CSubmappedOccupancyGrid3D,submappedOccupancyGrid3D",
	keygrid::CSubmappedOccupancyGrid3D)

// ---------------------------------------------------------------- map definition (INI)
CSubmappedOccupancyGrid3D::TMapDefinition::TMapDefinition() = default;

void CSubmappedOccupancyGrid3D::TMapDefinition::loadFromConfigFile_map_specific(
	const mrpt::config::CConfigFileBase& source, const std::string& prefix)
{
	const std::string sCreation = prefix + "_creationOpts";
	resolution = detail::readNumber(source, sCreation, "resolution", resolution);
	detail::require(resolution >= kMinResolution && resolution <= kMaxResolution, sCreation + "/resolution", resolution,
		"in [" + std::to_string(kMinResolution) + ", " + std::to_string(kMaxResolution) + "] m");
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
void CSubmappedOccupancyGrid3D::TInsertionOptions::loadFromConfigFile(
	const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	integration.loadFromConfigFile(c, s);
	conflict.loadFromConfigFile(c, s);
	storeKeyframeDepth = detail::readBool(c, s, "storeKeyframeDepth", storeKeyframeDepth);
	observationsAreKeyframes =
		detail::readBool(c, s, "observationsAreKeyframes", observationsAreKeyframes);
}

void CSubmappedOccupancyGrid3D::TInsertionOptions::saveToConfigFile(
	mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	integration.saveToConfigFile(c, s);
	conflict.saveToConfigFile(c, s);
	detail::writeBool(c, s, "storeKeyframeDepth", storeKeyframeDepth);
	detail::writeBool(c, s, "observationsAreKeyframes", observationsAreKeyframes);
}

void CSubmappedOccupancyGrid3D::TLikelihoodOptions::loadFromConfigFile(
	const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	const double d = detail::readNumber(c, s, "decimation", decimation);
	detail::require(d >= 1 && d == std::floor(d), "decimation", d, "an integer >= 1");
	decimation = static_cast<unsigned>(d);
	maxRange = detail::readNumber(c, s, "maxRange", maxRange);
	detail::require(maxRange > 0, "maxRange", maxRange, "> 0 m");
	minProbability = detail::readNumber(c, s, "minProbability", minProbability);
	detail::require(minProbability > 0 && minProbability < 0.5, "minProbability", minProbability,
		"in (0, 0.5)");
}

void CSubmappedOccupancyGrid3D::TLikelihoodOptions::saveToConfigFile(
	mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	detail::writeNumber(c, s, "decimation", decimation);
	detail::writeNumber(c, s, "maxRange", maxRange);
	detail::writeNumber(c, s, "minProbability", minProbability);
}

// ---------------------------------------------------------------- basics
CSubmappedOccupancyGrid3D::CSubmappedOccupancyGrid3D(double resolution)
{
	setResolution(resolution);
}

void CSubmappedOccupancyGrid3D::setResolution(double resolution)
{
	detail::require(resolution >= kMinResolution && resolution <= kMaxResolution, "resolution", resolution,
		"in [" + std::to_string(kMinResolution) + ", " + std::to_string(kMaxResolution) + "] m");
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
	for (const auto& kv : m_keyframes) b += kv.second.depth.total() * kv.second.depth.elemSize();
	return b;
}
