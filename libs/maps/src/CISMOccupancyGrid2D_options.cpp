/** \file CISMOccupancyGrid2D_options.cpp
 * Creation / insertion / likelihood options of CISMOccupancyGrid2D: INI load and save,
 * validation (an invalid value throws naming the key and the value).
 */
#include <keygrid/maps/CISMOccupancyGrid2D.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace keygrid
{
namespace
{
[[noreturn]] void badKey(const std::string& section, const std::string& key, const std::string& v,
	const std::string& why)
{
	throw std::invalid_argument(
		"[" + section + "] " + key + " = " + v + " is invalid: " + why);
}
std::string str(double v) { return std::to_string(v); }
}  // namespace

// ------------------------------------------------------------------ creation
void CISMOccupancyGrid2D::TCreationOptions::loadFromConfigFile(
	const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	resolution = c.read_double(s, "resolution", resolution);
	min_x = c.read_double(s, "min_x", min_x);
	max_x = c.read_double(s, "max_x", max_x);
	min_y = c.read_double(s, "min_y", min_y);
	max_y = c.read_double(s, "max_y", max_y);
	growthMargin = c.read_double(s, "growthMargin", growthMargin);
	try
	{
		validate();
	}
	catch (const std::invalid_argument& e)
	{
		throw std::invalid_argument("[" + s + "] " + e.what());
	}
}

void CISMOccupancyGrid2D::TCreationOptions::saveToConfigFile(
	mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	c.write(s, "resolution", resolution);
	c.write(s, "min_x", min_x);
	c.write(s, "max_x", max_x);
	c.write(s, "min_y", min_y);
	c.write(s, "max_y", max_y);
	c.write(s, "growthMargin", growthMargin);
}

void CISMOccupancyGrid2D::TCreationOptions::validate() const
{
	if (!(resolution > 0 && resolution < 10)) badKey("creationOpts", "resolution", str(resolution), "must be in (0, 10) m");
	if (!(max_x > min_x)) badKey("creationOpts", "max_x", str(max_x), "must exceed min_x = " + str(min_x));
	if (!(max_y > min_y)) badKey("creationOpts", "max_y", str(max_y), "must exceed min_y = " + str(min_y));
	if (!(growthMargin >= 0)) badKey("creationOpts", "growthMargin", str(growthMargin), "must be >= 0");
	const double cells = (max_x - min_x) / resolution * (max_y - min_y) / resolution;
	if (!(cells < 2.0e8)) badKey("creationOpts", "resolution", str(resolution), "extent has too many cells");
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

void CISMOccupancyGrid2D::TInsertionOptions::loadFromConfigFile(
	const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	pFree = c.read_double(s, "pFree", pFree);
	pOccupied = c.read_double(s, "pOccupied", pOccupied);
	pPrior = c.read_double(s, "pPrior", pPrior);
	bandWidth = c.read_double(s, "bandWidth", bandWidth);
	const std::string noise = c.read_string(s, "rangeNoise", maps::toString(rangeNoise));
	try
	{
		rangeNoise = maps::rangeNoiseModelFromString(noise);
	}
	catch (const std::invalid_argument&)
	{
		badKey(s, "rangeNoise", noise, "expected 'constant' or 'kinect'");
	}
	sigmaConstant = c.read_double(s, "sigmaConstant", sigmaConstant);
	logOddsMin = c.read_double(s, "logOddsMin", logOddsMin);
	logOddsMax = c.read_double(s, "logOddsMax", logOddsMax);
	maxRange = c.read_double(s, "maxRange", maxRange);
	obstacleMinHeight = c.read_double(s, "obstacleMinHeight", obstacleMinHeight);
	obstacleMaxHeight = c.read_double(s, "obstacleMaxHeight", obstacleMaxHeight);
	floorTolerance = c.read_double(s, "floorTolerance", floorTolerance);
	const std::string pose = c.read_string(s, "T_world_floor", "");
	if (!pose.empty())
	{
		try
		{
			T_world_floor.fromString(pose);
		}
		catch (const std::exception&)
		{
			badKey(s, "T_world_floor", pose, "expected \"[x y z yaw pitch roll]\" (m, deg)");
		}
	}
	estimateFloorFromDepth = c.read_bool(s, "estimateFloorFromDepth", estimateFloorFromDepth);
	const std::string up = c.read_string(s, "floorUpHint", "");
	if (!up.empty())
	{
		std::istringstream is(up);
		double x = 0, y = 0, z = 0;
		if (!(is >> x >> y >> z)) badKey(s, "floorUpHint", up, "expected three numbers \"x y z\"");
		floorUpHint = mrpt::math::TVector3D(x, y, z);
	}
	floorRansac.loadFromConfigFile(c, s);
	const std::string model = c.read_string(s, "freeSpaceModel", freeSpaceModel == FreeSpaceModel::HeightBand ? "heightBand" : "paper");
	if (model == "heightBand") freeSpaceModel = FreeSpaceModel::HeightBand;
	else if (model == "paper")
		freeSpaceModel = FreeSpaceModel::Paper;
	else
		badKey(s, "freeSpaceModel", model, "expected 'heightBand' or 'paper'");
	bandSliceHeight = c.read_double(s, "bandSliceHeight", bandSliceHeight);
	const std::string trav = c.read_string(s, "rayTraversal", rayTraversal == RayTraversal::Bresenham ? "bresenham" : "antialiased");
	if (trav == "bresenham") rayTraversal = RayTraversal::Bresenham;
	else if (trav == "antialiased")
		rayTraversal = RayTraversal::AntiAliased;
	else
		badKey(s, "rayTraversal", trav, "expected 'bresenham' or 'antialiased'");
	depthDecimation = c.read_int(s, "depthDecimation", depthDecimation);
	minPointsPerCell = c.read_int(s, "minPointsPerCell", minPointsPerCell);
	occupiedThreshold = c.read_double(s, "occupiedThreshold", occupiedThreshold);
	freeThreshold = c.read_double(s, "freeThreshold", freeThreshold);
	try
	{
		validate();
	}
	catch (const std::invalid_argument& e)
	{
		throw std::invalid_argument("[" + s + "] " + e.what());
	}
}

void CISMOccupancyGrid2D::TInsertionOptions::saveToConfigFile(
	mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	c.write(s, "pFree", pFree);
	c.write(s, "pOccupied", pOccupied);
	c.write(s, "pPrior", pPrior);
	c.write(s, "bandWidth", bandWidth);
	c.write(s, "rangeNoise", maps::toString(rangeNoise));
	c.write(s, "sigmaConstant", sigmaConstant);
	c.write(s, "logOddsMin", logOddsMin);
	c.write(s, "logOddsMax", logOddsMax);
	c.write(s, "maxRange", maxRange);
	c.write(s, "obstacleMinHeight", obstacleMinHeight);
	c.write(s, "obstacleMaxHeight", obstacleMaxHeight);
	c.write(s, "floorTolerance", floorTolerance);
	c.write(s, "T_world_floor", T_world_floor.asString());
	c.write(s, "estimateFloorFromDepth", estimateFloorFromDepth);
	c.write(s, "floorUpHint", std::to_string(floorUpHint.x) + " " + std::to_string(floorUpHint.y) + " " + std::to_string(floorUpHint.z));
	floorRansac.saveToConfigFile(c, s);
	c.write(s, "freeSpaceModel", freeSpaceModel == FreeSpaceModel::HeightBand ? "heightBand" : "paper");
	c.write(s, "bandSliceHeight", bandSliceHeight);
	c.write(s, "rayTraversal", rayTraversal == RayTraversal::Bresenham ? "bresenham" : "antialiased");
	c.write(s, "depthDecimation", depthDecimation);
	c.write(s, "minPointsPerCell", minPointsPerCell);
	c.write(s, "occupiedThreshold", occupiedThreshold);
	c.write(s, "freeThreshold", freeThreshold);
}

void CISMOccupancyGrid2D::TInsertionOptions::validate() const
{
	const std::string s = "insertOpts";
	try
	{
		ismShape(0.05).validate();
	}
	catch (const std::invalid_argument& e)
	{
		throw std::invalid_argument(std::string("insertOpts: ") + e.what());
	}
	if (!(bandWidth >= 0)) badKey(s, "bandWidth", str(bandWidth), "must be >= 0");
	if (!(sigmaConstant > 0)) badKey(s, "sigmaConstant", str(sigmaConstant), "must be > 0 m");
	const double l0 = maps::logit(pPrior);
	if (!(logOddsMin < l0)) badKey(s, "logOddsMin", str(logOddsMin), "must be below logit(pPrior) = " + str(l0));
	if (!(logOddsMax > l0)) badKey(s, "logOddsMax", str(logOddsMax), "must be above logit(pPrior) = " + str(l0));
	if (!(maxRange > 0)) badKey(s, "maxRange", str(maxRange), "must be > 0 m");
	if (!(obstacleMinHeight > floorTolerance))
		badKey(s, "obstacleMinHeight", str(obstacleMinHeight), "must exceed floorTolerance = " + str(floorTolerance));
	if (!(obstacleMaxHeight > obstacleMinHeight))
		badKey(s, "obstacleMaxHeight", str(obstacleMaxHeight), "must exceed obstacleMinHeight");
	if (!(floorTolerance >= 0)) badKey(s, "floorTolerance", str(floorTolerance), "must be >= 0 m");
	if (!(bandSliceHeight > 0)) badKey(s, "bandSliceHeight", str(bandSliceHeight), "must be > 0 m");
	if (!(std::ceil((obstacleMaxHeight - obstacleMinHeight) / bandSliceHeight - 1e-9) <= 64))
		badKey(s, "bandSliceHeight", str(bandSliceHeight), "the obstacle band may have at most 64 height slices");
	if (depthDecimation < 1) badKey(s, "depthDecimation", str(depthDecimation), "must be >= 1");
	if (minPointsPerCell < 1) badKey(s, "minPointsPerCell", str(minPointsPerCell), "must be >= 1");
	if (!(occupiedThreshold > pPrior && occupiedThreshold < 1))
		badKey(s, "occupiedThreshold", str(occupiedThreshold), "must be in (pPrior, 1)");
	if (!(freeThreshold > 0 && freeThreshold < pPrior))
		badKey(s, "freeThreshold", str(freeThreshold), "must be in (0, pPrior)");
	floorRansac.validate();
}

// ------------------------------------------------------------------ likelihood
void CISMOccupancyGrid2D::TLikelihoodOptions::loadFromConfigFile(
	const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	decimation = c.read_int(s, "decimation", decimation);
	outlierProbability = c.read_double(s, "outlierProbability", outlierProbability);
	try
	{
		validate();
	}
	catch (const std::invalid_argument& e)
	{
		throw std::invalid_argument("[" + s + "] " + e.what());
	}
}

void CISMOccupancyGrid2D::TLikelihoodOptions::saveToConfigFile(
	mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	c.write(s, "decimation", decimation);
	c.write(s, "outlierProbability", outlierProbability);
}

void CISMOccupancyGrid2D::TLikelihoodOptions::validate() const
{
	if (decimation < 1) badKey("likelihoodOpts", "decimation", str(decimation), "must be >= 1");
	if (!(outlierProbability > 0 && outlierProbability < 1))
		badKey("likelihoodOpts", "outlierProbability", str(outlierProbability), "must be in (0, 1)");
}

}  // namespace keygrid
