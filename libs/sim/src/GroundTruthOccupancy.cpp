#include <keygrid/core/AtomicOutput.h>
#include <keygrid/core/TumText.h>
#include <keygrid/sim/GroundTruthOccupancy.h>
#include <keygrid/sim/Scene.h>
#include <mrpt/system/filesystem.h>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace keygrid::sim
{
VoxelSet::VoxelSet(double resolution, const Eigen::Vector3d& origin)
	: m_res(resolution), m_origin(origin)
{
	if (!(resolution > 0)) throw std::invalid_argument("voxel resolution must be > 0");
}

VoxelSet::Index VoxelSet::indexOf(const Eigen::Vector3d& p) const
{
	Index v;
	for (int a = 0; a < 3; a++) v[a] = static_cast<int>(std::floor((p[a] - m_origin[a]) / m_res));
	return v;
}

Eigen::Vector3d VoxelSet::centre(const Index& v) const
{
	return m_origin + m_res * Eigen::Vector3d(v[0] + 0.5, v[1] + 0.5, v[2] + 0.5);
}

bool VoxelSet::contains(const Index& v) const
{
	return std::binary_search(m_voxels.begin(), m_voxels.end(), v);
}

void VoxelSet::finalize()
{
	std::sort(m_voxels.begin(), m_voxels.end());
	m_voxels.erase(std::unique(m_voxels.begin(), m_voxels.end()), m_voxels.end());
}

void VoxelSet::save(const std::string& path) const
{
	core::writeFileAtomically(path, [&](std::ostream& f) {
		f << "# keygrid ground-truth voxels: world frame (z up), metres.\n"
			 "# Voxel (i j k) is [origin + i*res, origin + (i+1)*res) per axis.\n"
			 "KEYGRID_VOXELS 1\n";
		char buf[128];
		std::snprintf(
			buf, sizeof(buf), "resolution %.9g\norigin %.9g %.9g %.9g\ncount %zu\n", m_res,
			m_origin.x(), m_origin.y(), m_origin.z(), m_voxels.size());
		f << buf;
		for (const auto& v : m_voxels) f << v[0] << ' ' << v[1] << ' ' << v[2] << '\n';
	});
}

VoxelSet VoxelSet::load(const std::string& path)
{
	const auto recs = core::readTumTextRecords(path);  // '#' comments, whitespace fields
	auto bad = [&](std::size_t line, const std::string& why) {
		return std::runtime_error(path + ":" + std::to_string(line) + ": " + why);
	};
	if (recs.size() < 4) throw std::runtime_error(path + ": too short for a KEYGRID_VOXELS file");
	const auto& h = recs[0];
	if (h.fields.size() != 2 || h.fields[0] != "KEYGRID_VOXELS")
		throw bad(h.line, "expected 'KEYGRID_VOXELS 1'");
	if (h.fields[1] != "1") throw bad(h.line, "unknown KEYGRID_VOXELS version " + h.fields[1]);
	auto num = [&](const core::TextRecord& r, std::size_t i) {
		double x = 0;
		if (i >= r.fields.size() || !core::parseDouble(r.fields[i], x))
			throw bad(r.line, "expected a number");
		return x;
	};
	if (recs[1].fields.size() != 2 || recs[1].fields[0] != "resolution")
		throw bad(recs[1].line, "expected 'resolution R'");
	if (recs[2].fields.size() != 4 || recs[2].fields[0] != "origin")
		throw bad(recs[2].line, "expected 'origin X Y Z'");
	if (recs[3].fields.size() != 2 || recs[3].fields[0] != "count")
		throw bad(recs[3].line, "expected 'count N'");
	const double res = num(recs[1], 1);
	if (!(res > 0)) throw bad(recs[1].line, "resolution must be > 0");
	VoxelSet vs(res, Eigen::Vector3d(num(recs[2], 1), num(recs[2], 2), num(recs[2], 3)));
	const double count = num(recs[3], 1);
	if (count != static_cast<double>(recs.size() - 4))
		throw bad(
			recs[3].line, "count " + recs[3].fields[1] + " but " + std::to_string(recs.size() - 4) +
							  " voxel lines");
	vs.m_voxels.reserve(recs.size() - 4);
	for (std::size_t i = 4; i < recs.size(); i++)
	{
		const auto& r = recs[i];
		if (r.fields.size() != 3) throw bad(r.line, "expected 'i j k'");
		Index v;
		for (int a = 0; a < 3; a++)
		{
			const double x = num(r, a);
			if (x != std::floor(x) || std::abs(x) > 1e9)
				throw bad(r.line, "voxel indices must be integers");
			v[a] = static_cast<int>(x);
		}
		vs.m_voxels.push_back(v);
	}
	vs.finalize();
	return vs;
}

std::array<int, 2> FloorPlan::cellOf(double x, double y) const
{
	return {
		static_cast<int>(std::floor((x - origin.x()) / resolution)),
		static_cast<int>(std::floor((y - origin.y()) / resolution))};
}

std::size_t FloorPlan::occupiedCount() const
{
	return static_cast<std::size_t>(std::count(occupied.begin(), occupied.end(), 1));
}

void FloorPlan::save(const std::string& stem) const
{
	cv::Mat img(height, width, CV_8UC1);
	for (int cy = 0; cy < height; cy++)
		for (int cx = 0; cx < width; cx++)
			img.at<std::uint8_t>(height - 1 - cy, cx) = occupied[cy * width + cx] ? 0 : 254;
	core::writeFileThrough(stem + ".pgm", [&](const std::string& tmp) { return cv::imwrite(tmp, img); });
	char buf[256];
	std::snprintf(
		buf, sizeof(buf),
		"image: %s.pgm\nresolution: %.9g\norigin: [%.9g, %.9g, 0.0]\nnegate: 0\n"
		"occupied_thresh: 0.65\nfree_thresh: 0.196\n",
		mrpt::system::extractFileName(stem).c_str(), resolution, origin.x(), origin.y());
	core::writeFileAtomically(stem + ".yaml", buf);
}

FloorPlan FloorPlan::load(const std::string& yamlPath)
{
	std::ifstream f(yamlPath);
	if (!f) throw std::runtime_error("cannot open '" + yamlPath + "'");
	std::string line, image;
	FloorPlan fp;
	double occThresh = 0.65;
	bool negate = false, haveRes = false, haveOrigin = false;
	while (std::getline(f, line))
	{
		const auto colon = line.find(':');
		if (colon == std::string::npos || line[0] == '#') continue;
		const std::string key = line.substr(0, colon);
		std::string val = line.substr(colon + 1);
		std::replace_if(
			val.begin(), val.end(), [](char c) { return c == '[' || c == ']' || c == ','; }, ' ');
		std::istringstream is(val);
		if (key == "image")
			is >> image;
		else if (key == "resolution")
			haveRes = static_cast<bool>(is >> fp.resolution);
		else if (key == "origin")
			haveOrigin = static_cast<bool>(is >> fp.origin.x() >> fp.origin.y());
		else if (key == "occupied_thresh")
			is >> occThresh;
		else if (key == "negate")
		{
			int n = 0;
			is >> n;
			negate = n != 0;
		}
	}
	if (image.empty() || !haveRes || !haveOrigin || !(fp.resolution > 0))
		throw std::runtime_error(yamlPath + ": needs image, resolution > 0 and origin");
	if (image[0] != '/') image = (std::filesystem::path(yamlPath).parent_path() / image).string();
	const cv::Mat img = cv::imread(image, cv::IMREAD_GRAYSCALE);
	if (img.empty()) throw std::runtime_error(yamlPath + ": cannot read image '" + image + "'");
	fp.width = img.cols;
	fp.height = img.rows;
	fp.occupied.assign(static_cast<std::size_t>(fp.width) * fp.height, 0);
	for (int cy = 0; cy < fp.height; cy++)
		for (int cx = 0; cx < fp.width; cx++)
		{
			const double v = img.at<std::uint8_t>(fp.height - 1 - cy, cx);
			const double p = negate ? v / 255.0 : (255.0 - v) / 255.0;
			fp.occupied[cy * fp.width + cx] = p > occThresh ? 1 : 0;
		}
	return fp;
}

VoxelSet voxeliseStaticScene(const Scene& scene, double resolution, const Eigen::Vector3d& origin)
{
	VoxelSet vs(resolution, origin);
	for (const auto& o : scene.objects)
	{
		if (o.dynamic) continue;
		o.shape.sampleSurface(
			resolution / 2, [&](const Eigen::Vector3d& p) { vs.insertPoint(o.T_world_obj * p); });
	}
	vs.finalize();
	return vs;
}

FloorPlan floorPlanOfStaticScene(const Scene& scene, double resolution, double zMin, double zMax)
{
	if (!(resolution > 0)) throw std::invalid_argument("floor-plan resolution must be > 0");
	if (!(zMin <= zMax)) throw std::invalid_argument("floor-plan band needs z_min <= z_max");
	Eigen::Vector3d lo, hi;
	if (!scene.staticBounds(lo, hi)) throw std::invalid_argument("the scene has no static object");
	FloorPlan fp;
	fp.resolution = resolution;
	fp.origin =
		Eigen::Vector2d(std::floor(lo.x() / resolution) - 1, std::floor(lo.y() / resolution) - 1) *
		resolution;
	fp.width = static_cast<int>(std::ceil((hi.x() - fp.origin.x()) / resolution)) + 1;
	fp.height = static_cast<int>(std::ceil((hi.y() - fp.origin.y()) / resolution)) + 1;
	fp.occupied.assign(static_cast<std::size_t>(fp.width) * fp.height, 0);
	for (const auto& o : scene.objects)
	{
		if (o.dynamic) continue;
		o.shape.sampleSurface(resolution / 2, [&](const Eigen::Vector3d& pl) {
			const Eigen::Vector3d p = o.T_world_obj * pl;
			if (p.z() < zMin || p.z() > zMax) return;
			// Closed cells: a point on a boundary (within the tolerance) marks both neighbours.
			const double e = kFloorPlanBoundaryTolerance;
			for (const double dx : {-e, e})
				for (const double dy : {-e, e})
				{
					const auto c = fp.cellOf(p.x() + dx, p.y() + dy);
					if (fp.inside(c[0], c[1])) fp.occupied[c[1] * fp.width + c[0]] = 1;
				}
		});
	}
	return fp;
}

}  // namespace keygrid::sim
