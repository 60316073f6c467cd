/** keygrid_ism2d_tum_map: builds a CISMOccupancyGrid2D from a TUM RGB-D folder with its
 * ground-truth poses (dense depth, every N-th frame as keyframe) and writes PREFIX.yaml/.pgm,
 * PREFIX.png and PREFIX_crop.png (observed area, 4x). Reproduces the figures in
 * doc/maps-ism2d.md, e.g.
 *   keygrid_ism2d_tum_map --input ../shared/data/tum_fr1_rpy_first250 --output /tmp/fr1rpy \
 *       --every 5 --floor ransac --up "0 0 1"
 */
#include <keygrid/core/CommandLine.h>
#include <keygrid/core/FrameSource.h>
#include <keygrid/core/RgbdObservation.h>
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <sstream>

namespace
{
/** Crops the observed (non-grey) part of a grid image with a margin and scales it 4x. */
void writeCrop(const std::string& in, const std::string& out)
{
	const cv::Mat m = cv::imread(in, cv::IMREAD_GRAYSCALE);
	if (m.empty()) throw std::runtime_error("cannot read " + in);
	int x0 = m.cols, y0 = m.rows, x1 = -1, y1 = -1;
	for (int r = 0; r < m.rows; r++)
		for (int c = 0; c < m.cols; c++)
			if (std::abs(int(m.at<uchar>(r, c)) - 128) > 2)
			{
				x0 = std::min(x0, c);
				x1 = std::max(x1, c);
				y0 = std::min(y0, r);
				y1 = std::max(y1, r);
			}
	if (x1 < 0) return;
	const int g = 4;
	cv::Rect roi(std::max(0, x0 - g), std::max(0, y0 - g), 0, 0);
	roi.width = std::min(m.cols, x1 + g + 1) - roi.x;
	roi.height = std::min(m.rows, y1 + g + 1) - roi.y;
	cv::Mat big;
	cv::resize(m(roi), big, cv::Size(), 4, 4, cv::INTER_NEAREST);
	if (!cv::imwrite(out, big)) throw std::runtime_error("cannot write " + out);
}

int run(int argc, char** argv)
{
	keygrid::core::CommandLine cl("keygrid_ism2d_tum_map", "2D ISM grid of a TUM RGB-D folder with ground-truth poses");
	cl.option("input", "TUM_DIR", "TUM folder (rgb/, depth/, groundtruth.txt)", true)
		.option("output", "PREFIX", "output prefix", true)
		.option("every", "N", "use every N-th frame as keyframe", false, "5")
		.option("floor", "world|ransac", "floor frame: world (z = 0, z up) or RANSAC on the first depth", false, "world")
		.option("up", "\"x y z\"", "up hint for --floor ransac (0 0 0 = camera -y)", false, "0 0 1");
	if (!cl.parse(argc, argv)) return 0;
	const std::string dir = cl.get("input"), out = cl.get("output");
	const long every = cl.getInt("every");
	if (every < 1) throw keygrid::core::CommandLineError("--every must be >= 1");
	auto src = keygrid::core::openFrameSource(dir);
	const auto gt = keygrid::core::readTumTrajectory(dir + "/groundtruth.txt");

	keygrid::CISMOccupancyGrid2D grid;
	if (cl.get("floor") == "ransac")
	{
		grid.insertionOptions.estimateFloorFromDepth = true;
		std::istringstream up(cl.get("up"));
		double x = 0, y = 0, z = 0;
		if (!(up >> x >> y >> z)) throw keygrid::core::CommandLineError("--up needs three numbers");
		grid.insertionOptions.floorUpHint = mrpt::math::TVector3D(x, y, z);
	}
	else if (cl.get("floor") != "world")
		throw keygrid::core::CommandLineError("--floor must be 'world' or 'ransac'");

	keygrid::core::Frame f;
	long n = 0;
	uint64_t kf = 0;
	double seconds = 0;
	while (src->next(f))
	{
		if (n++ % every) continue;
		const auto best = std::min_element(gt.begin(), gt.end(), [&](const auto& a, const auto& b) {
			return std::abs(a.t - f.timestamp) < std::abs(b.t - f.timestamp);
		});
		if (best == gt.end() || std::abs(best->t - f.timestamp) > 0.02) continue;
		const auto obs = keygrid::core::makeRgbdObservation(f);
		const auto t0 = std::chrono::steady_clock::now();
		if (grid.insertKeyframeDepth(kf, best->T_world_cam, *obs)) kf++;
		seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	}
	grid.saveAsRosMapServer(out + ".yaml");
	grid.saveAsImage(out + ".png");
	writeCrop(out + ".png", out + "_crop.png");
	std::cout << grid.asString() << "\nfloor pose in world: " << grid.floorPose() << "\n"
			  << kf << " keyframes, mean insertion " << (kf ? 1e3 * seconds / kf : 0.0) << " ms\n";
	return 0;
}
}  // namespace

int main(int argc, char** argv)
{
	try
	{
		return run(argc, argv);
	}
	catch (const std::exception& e)
	{
		std::cerr << "keygrid_ism2d_tum_map: " << e.what() << "\n";
		return 1;
	}
}
