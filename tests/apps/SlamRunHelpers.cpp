#include "SlamRunHelpers.h"

#include <keygrid/core/RawlogWriter.h>
#include <keygrid/core/RgbdObservation.h>
#include <opencv2/imgproc.hpp>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>

#include "TestData.h"

namespace keygrid::test
{
core::RgbdCamera smallCamera()
{
	core::RgbdCamera c;
	c.name = "small";
	c.width = 160;
	c.height = 120;
	c.fx = c.fy = 130.0;
	c.cx = 79.5;
	c.cy = 59.5;
	c.depthUnits = 0.001f;
	return c;
}

core::Frame texturedFrame(std::size_t i, float depthM)
{
	const core::RgbdCamera cam = smallCamera();
	// 8x8-pixel random blocks: plenty of FAST corners at every pyramid level.
	static const cv::Mat texture = [] {
		cv::Mat blocks(30, 120, CV_8UC1);
		cv::RNG rng(7);
		rng.fill(blocks, cv::RNG::UNIFORM, 0, 256);
		cv::Mat big;
		cv::resize(blocks, big, cv::Size(960, 240), 0, 0, cv::INTER_NEAREST);
		return big;
	}();
	const int x0 = static_cast<int>(i % 700);
	core::Frame f;
	f.index = i;
	f.timestamp = 1000.0 + static_cast<double>(i) / 30.0;
	f.camera = cam;
	f.grey = texture(cv::Rect(x0, 60, static_cast<int>(cam.width), static_cast<int>(cam.height))).clone();
	cv::cvtColor(f.grey, f.colour, cv::COLOR_GRAY2BGR);
	f.depth = cv::Mat(static_cast<int>(cam.height), static_cast<int>(cam.width), CV_32FC1, cv::Scalar(depthM));
	return f;
}

mrpt::obs::CObservation3DRangeScan::Ptr texturedObservation(std::size_t i, float depthM)
{
	return core::makeRgbdObservation(texturedFrame(i, depthM));
}

void writeRawlog(
	const std::string& path, const std::vector<mrpt::obs::CObservation3DRangeScan::Ptr>& obs, int compression)
{
	core::RawlogWriterOptions wo;
	wo.compressionLevel = compression;
	core::RawlogWriter w(path, wo);
	for (const auto& o : obs) w.write(o);
	w.close();
}

std::string writeFastConfig(const std::string& path, bool maps)
{
	std::ofstream f(path);
	f << "[slam]\nmode = sequential\ncamera = auto\n"
		 "[features]\ntype = orb\nnum_features = 500\nnum_levels = 4\n"
		 "[tracker]\nmin_init_features = 100\n"
		 "[refinement]\nglobal_bundle_adjustment = false\nrefine_frames = false\n"
		 "[loop_closing]\nenabled = false\n";
	if (maps)
		f << "[MappingApplication]\nismOccupancyGrid2D_count = 1\nsubmappedOccupancyGrid3D_count = 1\n"
			 "[MappingApplication_ismOccupancyGrid2D_00_creationOpts]\nresolution = 0.05\n"
			 "[MappingApplication_ismOccupancyGrid2D_00_insertOpts]\nestimateFloorFromDepth = true\n"
			 "[MappingApplication_submappedOccupancyGrid3D_00_creationOpts]\nresolution = 0.05\n"
			 "[MappingApplication_submappedOccupancyGrid3D_00_insertOpts]\nmaxRange = 4.0\n";
	return path;
}

bool ToolRun::signaled() const { return WIFSIGNALED(status); }
int ToolRun::termSignal() const { return WIFSIGNALED(status) ? WTERMSIG(status) : 0; }
int ToolRun::exitCode() const { return WIFEXITED(status) ? WEXITSTATUS(status) : -1; }

ToolRun runTool(const std::string& tool, const std::string& args, const std::string& env)
{
	ToolRun r;
	// `exec`: the shell becomes the tool, so a death by signal shows in the status.
	const std::string cmd = (env.empty() ? "" : env + " ") + "exec " + toolPath(tool) + " " + args + " 2>&1";
	FILE* p = popen(cmd.c_str(), "r");
	if (!p) return r;
	std::array<char, 4096> buf{};
	while (std::fgets(buf.data(), buf.size(), p)) r.output += buf.data();
	r.status = pclose(p);
	return r;
}

std::size_t countPoseLines(const std::string& path)
{
	std::ifstream f(path);
	std::string line;
	std::size_t n = 0;
	while (std::getline(f, line))
		if (!line.empty() && line[0] != '#') n++;
	return n;
}

}  // namespace keygrid::test
