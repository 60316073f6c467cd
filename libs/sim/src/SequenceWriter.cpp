#include "IniHelpers.h"
#include "SequenceOutput.h"

#include <keygrid/sim/GroundTruthOccupancy.h>
#include <keygrid/sim/Scene.h>
#include <keygrid/sim/SequenceWriter.h>
#include <keygrid/sim/Simulator.h>
#include <opencv2/core.hpp>

#include <chrono>
#include <cmath>
#include <stdexcept>

namespace keygrid::sim
{
void OutputOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	std::vector<std::string> keys;
	c.getAllKeys(s, keys);
	for (const auto& k : keys)
		if (k != "sensor" && k != "write_rawlog" && k != "write_tum" && k != "write_mask" &&
			k != "external_images" && k != "voxel_resolution" && k != "floorplan_resolution" &&
			k != "floorplan_z_min" && k != "floorplan_z_max" && k != "png_compression")
			throw std::invalid_argument("[" + s + "] unknown key '" + k + "'");
	if (const std::string v = ini::raw(c, s, "sensor"); v == "rgbd")
		sensor = RecordedSensor::Rgbd;
	else if (v == "monocular")
		sensor = RecordedSensor::Monocular;
	else if (!v.empty())
		ini::fail(s, "sensor", v, "must be rgbd or monocular");
	writeRawlog = ini::readBool(c, s, "write_rawlog", writeRawlog);
	writeTum = ini::readBool(c, s, "write_tum", writeTum);
	writeMask = ini::readBool(c, s, "write_mask", writeMask);
	externalImages = ini::readBool(c, s, "external_images", externalImages);
	voxelResolution = ini::readDouble(c, s, "voxel_resolution", voxelResolution, 0, 10);
	floorPlanResolution = ini::readDouble(c, s, "floorplan_resolution", floorPlanResolution, 0, 10);
	floorPlanZMin = ini::readDouble(c, s, "floorplan_z_min", floorPlanZMin, -1e3, 1e3);
	floorPlanZMax = ini::readDouble(c, s, "floorplan_z_max", floorPlanZMax, -1e3, 1e3);
	pngCompression = static_cast<int>(ini::readInt(c, s, "png_compression", pngCompression, 0, 9));
	if (voxelResolution > 0 && voxelResolution < 0.005)
		ini::fail(
			s, "voxel_resolution", ini::raw(c, s, "voxel_resolution"),
			"must be 0 (off) or >= 0.005 m");
	if (floorPlanResolution > 0 && floorPlanResolution < 0.005)
		ini::fail(
			s, "floorplan_resolution", ini::raw(c, s, "floorplan_resolution"),
			"must be 0 (off) or >= 0.005 m");
	if (!(floorPlanZMin <= floorPlanZMax))
		ini::fail(
			s, "floorplan_z_max", ini::raw(c, s, "floorplan_z_max"), "must be >= floorplan_z_min");
}

void OutputOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	auto b = [](bool v) { return std::string(v ? "true" : "false"); };
	c.write(s, "sensor", std::string(sensor == RecordedSensor::Monocular ? "monocular" : "rgbd"));
	c.write(s, "write_rawlog", b(writeRawlog));
	c.write(s, "write_tum", b(writeTum));
	c.write(s, "write_mask", b(writeMask));
	c.write(s, "external_images", b(externalImages));
	c.write(s, "voxel_resolution", voxelResolution);
	c.write(s, "floorplan_resolution", floorPlanResolution);
	c.write(s, "floorplan_z_min", floorPlanZMin);
	c.write(s, "floorplan_z_max", floorPlanZMax);
	c.write(s, "png_compression", pngCompression);
}

SequenceSummary writeSequence(
	const Scene& scene, const std::string& dir, const OutputOptions& o,
	const std::function<void(std::size_t, std::size_t)>& progress, unsigned threads, const std::function<bool()>& stop)
{
	if (scene.trajectory.empty())
		throw std::invalid_argument(
			"the scene has no [trajectory]: nothing to render a sequence from");
	using Clock = std::chrono::steady_clock;
	const auto t0 = Clock::now();
	makeDirectories(dir);
	SequenceSummary sum;
	scene.trajectory.maxSpeeds(scene.options.rateHz, sum.maxSpeed, sum.maxTurnRateDeg);
	sum.maxTurnRateDeg *= 180.0 / M_PI;

	// Ground truth of the static scene first: cheap, and useful even if rendering is stopped.
	if (o.voxelResolution > 0)
	{
		const VoxelSet vs = voxeliseStaticScene(scene, o.voxelResolution);
		vs.save(dir + "/occupancy_voxels.txt");
		sum.voxels = vs.size();
	}
	if (o.floorPlanResolution > 0)
	{
		const FloorPlan fp =
			floorPlanOfStaticScene(scene, o.floorPlanResolution, o.floorPlanZMin, o.floorPlanZMax);
		fp.save(dir + "/floorplan");
		sum.floorPlanCells = fp.occupiedCount();
	}

	const Simulator sim(scene, threads);
	SequenceOutput out(dir, scene.options.name, scene.camera, o);
	double dynSum = 0;
	const std::size_t n = scene.options.frames;
	for (std::size_t i = 0; i < n; i++)
	{
		if (stop && stop())
		{
			sum.stopped = true;
			break;
		}
		SimFrame& f = out.next();
		const auto r0 = Clock::now();
		sim.frame(i, f);
		sum.renderSeconds += std::chrono::duration<double>(Clock::now() - r0).count();
		dynSum += cv::countNonZero(f.dynamicMask) / static_cast<double>(f.dynamicMask.total());
		out.commit();
		if (progress) progress(i + 1, n);
	}
	out.close(
		"ground truth of keygrid-sim scene '" + scene.options.name +
		"': T_world_cam of the optical frame (x right, y down, z forward), world z up");
	sum.frames = out.count();
	sum.dynamicPixelFraction = sum.frames ? dynSum / static_cast<double>(sum.frames) : 0;
	sum.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
	return sum;
}

}  // namespace keygrid::sim
