#include <keygrid/core/AtomicOutput.h>
/** \file CISMOccupancyGrid2D_io.cpp
 * Versioned serialization, exports (ROS map_server pgm + yaml, image, COccupancyGridMap2D)
 * and the 3D visualization.
 */
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <keygrid/maps/ExportFrame.h>
#include <mrpt/img/CImage.h>
#include <mrpt/math/CQuaternion.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/serialization/CArchive.h>

#include <cstdio>
#include <fstream>
#include <stdexcept>

using namespace keygrid;
using mrpt::serialization::CArchive;

namespace
{
void writeOptions(CArchive& out, const CISMOccupancyGrid2D::TCreationOptions& c)
{
	out << c.resolution << c.min_x << c.max_x << c.min_y << c.max_y << c.growthMargin;
}
void readOptions(CArchive& in, CISMOccupancyGrid2D::TCreationOptions& c)
{
	in >> c.resolution >> c.min_x >> c.max_x >> c.min_y >> c.max_y >> c.growthMargin;
}
void writeOptions(CArchive& out, const CISMOccupancyGrid2D::TInsertionOptions& o)
{
	out << o.pFree << o.pOccupied << o.pPrior << o.bandWidth << static_cast<uint8_t>(o.rangeNoise)
		<< o.sigmaConstant << o.logOddsMin << o.logOddsMax << o.maxRange << o.obstacleMinHeight
		<< o.obstacleMaxHeight << o.floorTolerance << o.T_world_floor << o.estimateFloorFromDepth;
	// TVector3D is a packed struct: go through aligned locals.
	const double ux = o.floorUpHint.x, uy = o.floorUpHint.y, uz = o.floorUpHint.z;
	out << ux << uy << uz;
	const auto& r = o.floorRansac;
	out << r.inlierDistance << static_cast<int32_t>(r.iterations) << r.maxTiltDeg
		<< r.minInlierFraction << r.minCameraHeight << r.seed;
	out << static_cast<uint8_t>(o.rayTraversal) << static_cast<int32_t>(o.depthDecimation)
		<< static_cast<int32_t>(o.minPointsPerCell) << o.occupiedThreshold << o.freeThreshold;
	out << static_cast<uint8_t>(o.freeSpaceModel) << o.bandSliceHeight;  // since version 1
	out << o.floorReanchorShift;  // since version 2
	out << o.floorRayMargin;  // since version 3
}
void readOptions(CArchive& in, CISMOccupancyGrid2D::TInsertionOptions& o, uint8_t version)
{
	uint8_t noise = 0, trav = 0;
	int32_t iters = 0, dec = 0, minPts = 0;
	in >> o.pFree >> o.pOccupied >> o.pPrior >> o.bandWidth >> noise >> o.sigmaConstant >>
		o.logOddsMin >> o.logOddsMax >> o.maxRange >> o.obstacleMinHeight >>
		o.obstacleMaxHeight >> o.floorTolerance >> o.T_world_floor >> o.estimateFloorFromDepth;
	double ux = 0, uy = 0, uz = 0;
	in >> ux >> uy >> uz;
	o.floorUpHint = mrpt::math::TVector3D(ux, uy, uz);
	auto& r = o.floorRansac;
	in >> r.inlierDistance >> iters >> r.maxTiltDeg >> r.minInlierFraction >> r.minCameraHeight >>
		r.seed;
	in >> trav >> dec >> minPts >> o.occupiedThreshold >> o.freeThreshold;
	if (noise > 1 || trav > 1)
		throw std::runtime_error("CISMOccupancyGrid2D: corrupt enum in serialized options");
	o.rangeNoise = static_cast<maps::RangeNoiseModel>(noise);
	o.rayTraversal = static_cast<CISMOccupancyGrid2D::RayTraversal>(trav);
	r.iterations = iters;
	o.depthDecimation = dec;
	o.minPointsPerCell = minPts;
	// Version 0 grids were all built with the paper's free-space model.
	o.freeSpaceModel = CISMOccupancyGrid2D::FreeSpaceModel::Paper;
	if (version >= 1)
	{
		uint8_t model = 0;
		in >> model >> o.bandSliceHeight;
		if (model > 1) throw std::runtime_error("CISMOccupancyGrid2D: corrupt freeSpaceModel in serialized options");
		o.freeSpaceModel = static_cast<CISMOccupancyGrid2D::FreeSpaceModel>(model);
	}
	// Older grids take the compiled-in default (it only decides future floor changes).
	o.floorReanchorShift = CISMOccupancyGrid2D::TInsertionOptions().floorReanchorShift;
	if (version >= 2) in >> o.floorReanchorShift;
	o.floorRayMargin = 0.0;  // older grids cleared the whole ray
	if (version >= 3) in >> o.floorRayMargin;
}
}  // namespace

uint8_t CISMOccupancyGrid2D::serializeGetVersion() const { return 3; }

void CISMOccupancyGrid2D::serializeTo(CArchive& out) const
{
	writeOptions(out, creationOptions);
	writeOptions(out, insertionOptions);
	out << static_cast<int32_t>(likelihoodOptions.decimation) << likelihoodOptions.outlierProbability;
	out << genericMapParams;
	out << m_resolution << m_xMin << m_yMin << static_cast<int32_t>(m_sizeX)
		<< static_cast<int32_t>(m_sizeY) << m_logOdds;
	out << m_floorEstimated << m_T_world_floorEstimate;
	out << static_cast<uint64_t>(m_keyframes.size());
	for (const auto& [id, kf] : m_keyframes)
	{
		out << id << kf.T_world_cam << static_cast<uint64_t>(kf.points_cam.size());
		for (const auto& p : kf.points_cam)
		{
			const float x = p.x, y = p.y, z = p.z;  // packed struct: aligned copies
			out << x << y << z;
		}
	}
	out << m_nextAutoKeyframeId << m_lastRebuildSeconds;
	out << static_cast<int32_t>(m_bandSlices) << m_band << m_floorExternal;  // since version 1
}

void CISMOccupancyGrid2D::serializeFrom(CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0:
		case 1:
		case 2:
		case 3:
		{
			readOptions(in, creationOptions);
			readOptions(in, insertionOptions, version);
			int32_t dec = 0;
			in >> dec >> likelihoodOptions.outlierProbability;
			likelihoodOptions.decimation = dec;
			in >> genericMapParams;
			int32_t sx = 0, sy = 0;
			in >> m_resolution >> m_xMin >> m_yMin >> sx >> sy >> m_logOdds;
			if (sx < 0 || sy < 0 || m_logOdds.size() != static_cast<size_t>(sx) * static_cast<size_t>(sy))
				throw std::runtime_error("CISMOccupancyGrid2D: serialized grid size mismatch");
			m_sizeX = sx;
			m_sizeY = sy;
			in >> m_floorEstimated >> m_T_world_floorEstimate;
			uint64_t nKf = 0;
			in >> nKf;
			m_keyframes.clear();
			for (uint64_t k = 0; k < nKf; k++)
			{
				uint64_t id = 0, nPts = 0;
				KeyframeRays kf;
				in >> id >> kf.T_world_cam >> nPts;
				kf.points_cam.resize(nPts);
				for (auto& p : kf.points_cam)
				{
					float x = 0, y = 0, z = 0;
					in >> x >> y >> z;
					p = mrpt::math::TPoint3Df(x, y, z);
				}
				m_keyframes[id] = std::move(kf);
			}
			in >> m_nextAutoKeyframeId >> m_lastRebuildSeconds;
			m_band.clear();
			m_bandSlices = 0;
			m_floorExternal = false;
			if (version >= 1)
			{
				int32_t slices = 0;
				in >> slices >> m_band >> m_floorExternal;
				if (!m_band.empty() && (slices < 1 || slices > 64 || m_band.size() != m_logOdds.size() * static_cast<size_t>(slices + 1)))
					throw std::runtime_error("CISMOccupancyGrid2D: serialized height band size mismatch");
				m_bandSlices = m_band.empty() ? 0 : slices;
			}
			m_scratch.assign(m_logOdds.size(), 0.0f);
			m_bandScratch.clear();
			m_touched.clear();
			m_bandTouched.clear();
		}
		break;
		default: MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	}
}

// ------------------------------------------------------------------ exports
void CISMOccupancyGrid2D::saveAsRosMapServer(const std::string& yamlPath) const
{
	const auto dot = yamlPath.find_last_of('.');
	const auto slash = yamlPath.find_last_of('/');
	const std::string stem =
		(dot != std::string::npos && (slash == std::string::npos || dot > slash)) ? yamlPath.substr(0, dot) : yamlPath;
	const std::string pgmPath = stem + ".pgm";
	const std::string pgmName = slash == std::string::npos ? pgmPath : pgmPath.substr(slash + 1);

	// map_server trinary convention: p = (255 - v) / 255 with v = 0 occupied, 254 free, 205 unknown.
	core::writeFileAtomically(pgmPath, [&](std::ostream& pgm) {
		pgm << "P5\n# keygrid::CISMOccupancyGrid2D\n" << m_sizeX << " " << m_sizeY << "\n255\n";
		std::vector<unsigned char> row(static_cast<size_t>(m_sizeX));
		for (int r = 0; r < m_sizeY; r++)
		{
			const int cy = m_sizeY - 1 - r;  // image row 0 is the top = largest y
			for (int cx = 0; cx < m_sizeX; cx++)
			{
				const CellState s = cellState(cx, cy);
				row[static_cast<size_t>(cx)] = s == CellState::Occupied ? 0 : s == CellState::Free ? 254 : 205;
			}
			pgm.write(reinterpret_cast<const char*>(row.data()), static_cast<std::streamsize>(row.size()));
		}
	});

	char buf[512];
	std::snprintf(buf, sizeof(buf),
		"image: %s\nresolution: %.9g\norigin: [%.9g, %.9g, 0.0]\nnegate: 0\n"
		"occupied_thresh: 0.65\nfree_thresh: 0.196\n",
		pgmName.c_str(), m_resolution, m_xMin, m_yMin);
	// The floor frame in the world (a comment: map_server and MRPT ignore it), so that a map
	// whose floor was estimated can be compared with a ground truth in another frame. First
	// line: libfyaml 0.8 (MRPT's YAML reader) leaks its input buffer on a trailing comment.
	core::writeFileAtomically(yamlPath, "# " + maps::floorFrameComment(floorPose()) + "\n" + buf);
}

namespace
{
mrpt::img::CImage toGreyImage(const CISMOccupancyGrid2D& g)
{
	mrpt::img::CImage img(static_cast<unsigned>(g.sizeX()), static_cast<unsigned>(g.sizeY()), mrpt::img::CH_GRAY);
	for (int r = 0; r < g.sizeY(); r++)
	{
		auto* line = img.ptrLine<uint8_t>(static_cast<unsigned>(r));
		const int cy = g.sizeY() - 1 - r;
		for (int cx = 0; cx < g.sizeX(); cx++)
			line[cx] = static_cast<uint8_t>(std::lround(255.0 * (1.0 - g.occupancy(cx, cy))));
	}
	return img;
}
}  // namespace

void CISMOccupancyGrid2D::saveAsImage(const std::string& file) const
{
	const auto img = toGreyImage(*this);
	core::writeFileThrough(file, [&](const std::string& tmp) { return img.saveToFile(tmp); });
}

mrpt::maps::COccupancyGridMap2D CISMOccupancyGrid2D::toOccupancyGridMap2D() const
{
	const float res = static_cast<float>(m_resolution);
	mrpt::maps::COccupancyGridMap2D g(
		static_cast<float>(m_xMin), static_cast<float>(xMax()), static_cast<float>(m_yMin),
		static_cast<float>(yMax()), res);
	// MRPT grid cells hold the probability of being FREE (white = 1 in its bitmaps).
	for (int cy = 0; cy < m_sizeY; cy++)
		for (int cx = 0; cx < m_sizeX; cx++)
			g.setPos(static_cast<float>(idx2x(cx)), static_cast<float>(idx2y(cy)),
				static_cast<float>(1.0 - occupancy(cx, cy)));
	return g;
}

void CISMOccupancyGrid2D::saveMetricMapRepresentationToFile(const std::string& prefix) const
{
	saveAsRosMapServer(prefix + ".yaml");
	saveAsImage(prefix + ".png");
}

void CISMOccupancyGrid2D::getVisualizationInto(mrpt::opengl::CSetOfObjects& outObj) const
{
	if (!genericMapParams.enableSaveAs3DObject) return;
	// MRPT's own textured-plane rendering of the converted grid, placed at the floor pose.
	// (Creating the mrpt::opengl::CTexturedPlane inside libmrpt-maps also keeps its inline
	// destructor out of our code: GCC lays out its over-aligned virtual base at a 16-byte
	// offset, which UBSan reports as a misaligned member call.)
	auto floorObjs = mrpt::opengl::CSetOfObjects::Create();
	toOccupancyGridMap2D().getVisualizationInto(*floorObjs);
	floorObjs->setPose(floorPose());
	outObj.insert(floorObjs);
}
