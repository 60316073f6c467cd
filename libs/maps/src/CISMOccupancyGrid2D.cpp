/** \file CISMOccupancyGrid2D.cpp
 * Construction, MAP_DEFINITION (INI creation), cell access and grid growth.
 * Insertion: CISMOccupancyGrid2D_insert.cpp; serialization and exports: _io.cpp.
 */
#include "detail/MapDefinitionSections.h"

#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <mrpt/maps/CMultiMetricMap.h>

#include <algorithm>
#include <cmath>
#include <sstream>

using namespace keygrid;

//  =========== Begin of Map definition ============
MAP_DEFINITION_REGISTER("keygrid::CISMOccupancyGrid2D,ismOccupancyGrid2D", keygrid::CISMOccupancyGrid2D)

CISMOccupancyGrid2D::TMapDefinition::TMapDefinition() = default;

void CISMOccupancyGrid2D::TMapDefinition::loadFromConfigFile_map_specific(
	const mrpt::config::CConfigFileBase& source, const std::string& sectionNamePrefix)
{
	optionSection = sectionNamePrefix;
	detail::loadMapSections(source, sectionNamePrefix, creationOpts, insertionOpts, likelihoodOpts);
}

void CISMOccupancyGrid2D::TMapDefinition::dumpToTextStream_map_specific(std::ostream& out) const
{
	detail::dumpMapSections(out, creationOpts, insertionOpts, likelihoodOpts);
}

mrpt::maps::CMetricMap* CISMOccupancyGrid2D::internal_CreateFromMapDefinition(
	const mrpt::maps::TMetricMapInitializer& _def)
{
	const auto& def = dynamic_cast<const CISMOccupancyGrid2D::TMapDefinition&>(_def);
	auto* obj = new CISMOccupancyGrid2D(def.creationOpts);
	obj->insertionOptions = def.insertionOpts;
	obj->likelihoodOptions = def.likelihoodOpts;
	obj->m_optionSection = def.optionSection;
	return obj;
}
//  =========== End of Map definition Block =========

IMPLEMENTS_SERIALIZABLE(CISMOccupancyGrid2D, CMetricMap, keygrid)

CISMOccupancyGrid2D::CISMOccupancyGrid2D() { resetGeometry(creationOptions); }

CISMOccupancyGrid2D::CISMOccupancyGrid2D(const TCreationOptions& creation)
{
	creation.validate();
	creationOptions = creation;
	resetGeometry(creationOptions);
}

void CISMOccupancyGrid2D::resetGeometry(const TCreationOptions& c)
{
	m_resolution = c.resolution;
	m_xMin = c.min_x;
	m_yMin = c.min_y;
	m_sizeX = std::max(1, static_cast<int>(std::ceil((c.max_x - c.min_x) / c.resolution - 1e-9)));
	m_sizeY = std::max(1, static_cast<int>(std::ceil((c.max_y - c.min_y) / c.resolution - 1e-9)));
	m_logOdds.assign(static_cast<size_t>(m_sizeX) * m_sizeY, 0.0f);
	m_scratch.assign(m_logOdds.size(), 0.0f);
	m_touched.clear();
	m_band.clear();
	m_bandScratch.clear();
	m_bandTouched.clear();
	m_bandSlices = 0;
}

int CISMOccupancyGrid2D::bandSlicesWanted() const
{
	const auto& o = insertionOptions;
	return std::max(1, static_cast<int>(std::ceil((o.obstacleMaxHeight - o.obstacleMinHeight) / o.bandSliceHeight - 1e-9)));
}

void CISMOccupancyGrid2D::resetBand()
{
	m_bandSlices = bandSlicesWanted();
	const size_t n = m_logOdds.size() * static_cast<size_t>(m_bandSlices + 1);
	m_band.assign(n, 0.0f);
	m_bandScratch.clear();  // sized per keyframe window (integrateRays)
	m_bandTouched.clear();
}

float CISMOccupancyGrid2D::columnLogOdds(size_t cell) const
{
	const size_t stride = static_cast<size_t>(m_bandSlices + 1);
	const float* v = &m_band[cell * stride];
	const float strongest = *std::max_element(v + 1, v + stride);
	return strongest > 0.0f ? strongest : v[0];
}

void CISMOccupancyGrid2D::internal_clear()
{
	resetGeometry(creationOptions);
	m_keyframes.clear();
	m_waitingForFloor.clear();
	m_floorEstimated = false;
	m_T_world_floorEstimate = mrpt::poses::CPose3D();
	m_lastRebuildSeconds = 0;
}

void CISMOccupancyGrid2D::growToContain(double x0, double x1, double y0, double y1)
{
	if (x0 >= m_xMin && y0 >= m_yMin && x1 < xMax() && y1 < yMax()) return;
	const double margin = creationOptions.growthMargin;
	// New bounds, kept on the old cell lattice so that existing cells move by whole cells.
	const int addLeft = x0 < m_xMin ? static_cast<int>(std::ceil((m_xMin - x0 + margin) / m_resolution)) : 0;
	const int addBottom = y0 < m_yMin ? static_cast<int>(std::ceil((m_yMin - y0 + margin) / m_resolution)) : 0;
	const int addRight = x1 >= xMax() ? static_cast<int>(std::ceil((x1 - xMax() + margin) / m_resolution)) + 1 : 0;
	const int addTop = y1 >= yMax() ? static_cast<int>(std::ceil((y1 - yMax() + margin) / m_resolution)) + 1 : 0;
	const int nx = m_sizeX + addLeft + addRight;
	const int ny = m_sizeY + addBottom + addTop;
	if (static_cast<double>(nx) * ny > 2.0e8)
		throw std::runtime_error(
			"CISMOccupancyGrid2D: growing to " + std::to_string(nx) + "x" + std::to_string(ny) +
			" cells refused (points far away? check maxRange and the floor frame)");
	std::vector<float> grown(static_cast<size_t>(nx) * ny, 0.0f);
	for (int cy = 0; cy < m_sizeY; cy++)
		std::copy_n(&m_logOdds[static_cast<size_t>(cy) * m_sizeX], m_sizeX,
			&grown[static_cast<size_t>(cy + addBottom) * nx + addLeft]);
	m_logOdds.swap(grown);
	if (!m_band.empty())
	{
		// The band values move with their cells: same copy, bandStride values per cell.
		const size_t stride = static_cast<size_t>(m_bandSlices + 1);
		std::vector<float> band(static_cast<size_t>(nx) * ny * stride, 0.0f);
		for (int cy = 0; cy < m_sizeY; cy++)
			std::copy_n(&m_band[static_cast<size_t>(cy) * m_sizeX * stride], static_cast<size_t>(m_sizeX) * stride,
				&band[(static_cast<size_t>(cy + addBottom) * nx + addLeft) * stride]);
		m_band.swap(band);
	}
	m_xMin -= addLeft * m_resolution;
	m_yMin -= addBottom * m_resolution;
	m_sizeX = nx;
	m_sizeY = ny;
	m_scratch.assign(m_logOdds.size(), 0.0f);
	m_touched.clear();
}

float CISMOccupancyGrid2D::logOdds(int cx, int cy) const
{
	if (!inside(cx, cy)) return 0.0f;
	return m_logOdds[static_cast<size_t>(cx) + static_cast<size_t>(cy) * m_sizeX];
}

double CISMOccupancyGrid2D::occupancy(int cx, int cy) const
{
	// Stored values are l - l0 accumulated, so p = logistic(l0 + stored).
	return maps::logistic(maps::logit(insertionOptions.pPrior) + logOdds(cx, cy));
}

CellState CISMOccupancyGrid2D::cellState(int cx, int cy) const
{
	const double p = occupancy(cx, cy);
	if (p >= insertionOptions.occupiedThreshold) return CellState::Occupied;
	if (p <= insertionOptions.freeThreshold) return CellState::Free;
	return CellState::Unknown;
}

std::array<size_t, 3> CISMOccupancyGrid2D::countStates() const
{
	std::array<size_t, 3> n{0, 0, 0};
	for (int cy = 0; cy < m_sizeY; cy++)
		for (int cx = 0; cx < m_sizeX; cx++) n[static_cast<size_t>(cellState(cx, cy))]++;
	return n;
}

bool CISMOccupancyGrid2D::isEmpty() const
{
	return std::all_of(m_logOdds.begin(), m_logOdds.end(), [](float l) { return l == 0.0f; });
}

std::string CISMOccupancyGrid2D::asString() const
{
	const auto n = countStates();
	std::ostringstream s;
	s << "keygrid::CISMOccupancyGrid2D " << m_sizeX << "x" << m_sizeY << " cells of "
	  << m_resolution << " m, x=[" << m_xMin << "," << xMax() << "] y=[" << m_yMin << ","
	  << yMax() << "], occupied=" << n[2] << " free=" << n[1] << " unknown=" << n[0]
	  << ", keyframes=" << m_keyframes.size();
	return s.str();
}
