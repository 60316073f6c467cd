/** \file CISMOccupancyGrid2D_options.cpp
 * Creation / insertion / likelihood options of CISMOccupancyGrid2D: their INI tables
 * (core::OptionFields) and the checks that relate two fields. An invalid value throws naming
 * [section], key and value.
 */
#include "detail/OptionValues.h"

#include <keygrid/maps/CISMOccupancyGrid2D.h>

#include <cmath>
#include <stdexcept>

namespace keygrid
{
namespace
{
/** The error of a check between two fields, in the form of core::OptionFields' errors. */
[[noreturn]] void badValue(const std::string& section, const std::string& key, double value, const std::string& rule)
{
	throw std::invalid_argument("[" + section + "] " + key + " = " + std::to_string(value) + " (must be " + rule + ")");
}
}  // namespace

// ------------------------------------------------------------------ creation
core::OptionFields CISMOccupancyGrid2D::TCreationOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("resolution", resolution, "cell edge [m]", R::between(0, 10));
	f.add("min_x", min_x, "initial extent in the floor frame, lowest x [m]; the grid grows to hold every ray");
	f.add("max_x", max_x, "initial extent, highest x [m] (> min_x)");
	f.add("min_y", min_y, "initial extent, lowest y [m]");
	f.add("max_y", max_y, "initial extent, highest y [m] (> min_y)");
	f.add("growthMargin", growthMargin, "a growing grid extends this far beyond the rays that made it grow [m]", R::atLeast(0));
	return f;
}

void CISMOccupancyGrid2D::TCreationOptions::validate(const std::string& s) const
{
	core::validateFields(*this, s);
	if (!(max_x > min_x)) badValue(s, "max_x", max_x, "> min_x = " + std::to_string(min_x));
	if (!(max_y > min_y)) badValue(s, "max_y", max_y, "> min_y = " + std::to_string(min_y));
	const double cells = (max_x - min_x) / resolution * (max_y - min_y) / resolution;
	if (!(cells < 2.0e8)) badValue(s, "resolution", resolution, "coarse enough for fewer than 2e8 cells in the initial extent");
}

// ------------------------------------------------------------------ insertion
maps::IsmShape CISMOccupancyGrid2D::TInsertionOptions::ismShape(double resolution) const
{
	maps::IsmShape s;
	s.pFree = pFree;
	s.pOccupied = pOccupied;
	s.pPrior = pPrior;
	s.bandWidth = bandWidth > 0 ? bandWidth : resolution * std::sqrt(2.0);
	return s;
}

core::OptionFields CISMOccupancyGrid2D::TInsertionOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("pFree", pFree, "ideal ISM: occupancy of the cells nearer than the band, r < z - L/2 (< pPrior)", R::between(0, 1));
	f.add("pOccupied", pOccupied, "ideal ISM: occupancy inside the band around the measured range z, |r - z| <= L/2 (> pPrior)", R::between(0, 1));
	f.add("pPrior", pPrior, "prior occupancy p0: unknown cells, and the ISM beyond the band; l0 = logit(p0)", R::between(0, 1));
	f.add("bandWidth", bandWidth, "width L of the ISM's occupied band [m]; 0 = the cell diagonal, resolution*sqrt(2)", R::atLeast(0));
	f.addCustom(
		"rangeNoise",
		{[this](const std::string& text) {
			 try
			 {
				 rangeNoise = maps::rangeNoiseModelFromString(text);  // any letter case
			 }
			 catch (const std::invalid_argument&)
			 {
				 throw std::invalid_argument("expected 'constant' or 'kinect'");
			 }
		 },
		 [this] { return maps::toString(rangeNoise); }},
		"range noise sigma blurring the ISM's band: constant (sigmaConstant) or kinect (0.0012 + 0.0019 (d - 0.4)^2 m at depth d)",
		R::oneOf({"constant", "kinect"}));
	f.add("sigmaConstant", sigmaConstant, "range noise sigma of rangeNoise = constant [m]", R::positive());
	f.add("logOddsMin", logOddsMin, "lower clamp of a cell's log-odds (< logit(pPrior))");
	f.add("logOddsMax", logOddsMax, "upper clamp of a cell's log-odds (> logit(pPrior))");
	f.add("maxRange", maxRange, "points farther than this from the camera, measured horizontally, are ignored [m]", R::positive());
	f.add("obstacleMinHeight", obstacleMinHeight, "obstacle band above the floor, lower end [m] (> floorTolerance)");
	f.add("obstacleMaxHeight", obstacleMaxHeight, "obstacle band, upper end [m] (> obstacleMinHeight); points above it are ignored");
	f.add("floorTolerance", floorTolerance, "points within +- this of the floor are floor: their rays only clear space [m]", R::atLeast(0));
	f.add("floorRayMargin", floorRayMargin, "a floor point's ray clears space up to this short of the point [m]", R::atLeast(0));
	f.addCustom(
		"T_world_floor",
		{[this](const std::string& text) {
			 mrpt::poses::CPose3D pose;
			 try
			 {
				 pose.fromString(text);
			 }
			 catch (const std::exception&)
			 {
				 throw std::invalid_argument("expected \"[x y z yaw pitch roll]\" (m, deg)");
			 }
			 T_world_floor = pose;
		 },
		 [this] { return T_world_floor.asString(); }},
		"floor frame (z up, z = 0 on the floor) in the world [x y z yaw pitch roll] (m, deg); keygrid-slam: use [floor]");
	f.addCustom(
		"estimateFloorFromDepth", detail::flagValue(estimateFloorFromDepth),
		"estimate the floor by RANSAC from the first depth image instead of T_world_floor; keygrid-slam: use [floor]");
	f.addCustom(
		"floorUpHint", detail::vectorValue(floorUpHint), "\"up\" in the world (x y z) for that estimate; 0 0 0 = the camera's -y axis");
	f.append(floorRansac.fields());
	f.add("floorReanchorShift", floorReanchorShift,
		  "keygrid-slam: a new floor estimate re-integrates the keyframes only if it moves a point of the grid by more than this [m] (0: always)",
		  R::atLeast(0));
	detail::addWords(
		f, "freeSpaceModel", freeSpaceModel, {{"heightBand", FreeSpaceModel::HeightBand}, {"paper", FreeSpaceModel::Paper}},
		"heightBand: rays clear only the band slices they cross, never obstacles above or below them; paper: all cells before a hit");
	f.add("bandSliceHeight", bandSliceHeight, "heightBand: thickness of the obstacle band's height slices [m] (at most 64 slices)", R::positive());
	detail::addWords(
		f, "rayTraversal", rayTraversal, {{"bresenham", RayTraversal::Bresenham}, {"antialiased", RayTraversal::AntiAliased}},
		"cells a ray updates: bresenham (one per step) or antialiased (Wu: two per step, weights summing to 1)");
	f.add("depthDecimation", depthDecimation, "dense depth: use every n-th pixel in rows and columns", R::atLeast(1));
	f.add("minPointsPerCell", minPointsPerCell, "dense depth: obstacle points an endpoint cell needs before it casts a ray (rejects speckle)", R::atLeast(1));
	f.add("occupiedThreshold", occupiedThreshold, "a cell whose occupancy is >= this reads occupied (> pPrior)", R::between(0, 1));
	f.add("freeThreshold", freeThreshold, "a cell whose occupancy is <= this reads free (< pPrior)", R::between(0, 1));
	return f;
}

void CISMOccupancyGrid2D::TInsertionOptions::validate(const std::string& s) const
{
	core::validateFields(*this, s);  // also the floorRansac_ keys
	const std::string prior = "pPrior = " + std::to_string(pPrior);
	if (!(pFree < pPrior)) badValue(s, "pFree", pFree, "< " + prior);
	if (!(pOccupied > pPrior)) badValue(s, "pOccupied", pOccupied, "> " + prior);
	const std::string l0 = "logit(pPrior) = " + std::to_string(maps::logit(pPrior));
	if (!(logOddsMin < maps::logit(pPrior))) badValue(s, "logOddsMin", logOddsMin, "< " + l0);
	if (!(logOddsMax > maps::logit(pPrior))) badValue(s, "logOddsMax", logOddsMax, "> " + l0);
	if (!(obstacleMinHeight > floorTolerance))
		badValue(s, "obstacleMinHeight", obstacleMinHeight, "> floorTolerance = " + std::to_string(floorTolerance));
	if (!(obstacleMaxHeight > obstacleMinHeight))
		badValue(s, "obstacleMaxHeight", obstacleMaxHeight, "> obstacleMinHeight = " + std::to_string(obstacleMinHeight));
	if (!(std::ceil((obstacleMaxHeight - obstacleMinHeight) / bandSliceHeight - 1e-9) <= 64))
		badValue(s, "bandSliceHeight", bandSliceHeight, "thick enough for at most 64 slices in the obstacle band");
	if (!(occupiedThreshold > pPrior)) badValue(s, "occupiedThreshold", occupiedThreshold, "> " + prior);
	if (!(freeThreshold < pPrior)) badValue(s, "freeThreshold", freeThreshold, "< " + prior);
}

// ------------------------------------------------------------------ likelihood
core::OptionFields CISMOccupancyGrid2D::TLikelihoodOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("decimation", decimation, "use every n-th depth pixel in rows and columns", R::atLeast(1));
	f.add("outlierProbability", outlierProbability, "eps of each obstacle-band point's likelihood eps + (1 - eps) p(cell)", R::between(0, 1));
	return f;
}

}  // namespace keygrid
