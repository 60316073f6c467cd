/** \file make_seeds.cpp
 * Writes the seed corpora of the fuzz targets into DIR/<target>/: small valid inputs made by
 * keygrid's own writers (a rawlog of three 40x30 RGB-D observations, plain and gzip; PNGs of
 * every kind the fast decoder handles; TUM lists; INI files), so that fuzzing starts from
 * inputs that reach deep into each parser. Usage: keygrid_fuzz_make_seeds DIR SOURCE_DIR
 */
#include <keygrid/core/RawlogWriter.h>
#include <keygrid/core/RgbdObservation.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace fs = std::filesystem;

namespace
{
keygrid::core::Frame tinyFrame(int i)
{
	keygrid::core::Frame f;
	f.index = static_cast<std::size_t>(i);
	f.timestamp = 1000.0 + 0.033 * i;
	f.camera.width = 40;
	f.camera.height = 30;
	f.camera.fx = f.camera.fy = 40.0;
	f.camera.cx = 19.5;
	f.camera.cy = 14.5;
	f.colour = cv::Mat(30, 40, CV_8UC3);
	cv::randu(f.colour, 0, 256);
	cv::cvtColor(f.colour, f.grey, cv::COLOR_BGR2GRAY);
	f.depth = cv::Mat(30, 40, CV_32FC1, cv::Scalar(1.5f + 0.1f * i));
	return f;
}

void writeText(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }
}  // namespace

int main(int argc, char** argv)
{
	if (argc != 3)
	{
		std::fprintf(stderr, "usage: %s DIR SOURCE_DIR\n", argv[0]);
		return 2;
	}
	const fs::path dir = argv[1], src = argv[2];
	for (const char* t : {"rawlog", "tum", "ini", "png"}) fs::create_directories(dir / t);
	cv::setRNGSeed(1);

	for (const int level : {0, 1})
	{
		keygrid::core::RawlogWriterOptions o;
		o.compressionLevel = level;
		keygrid::core::RawlogWriter w((dir / "rawlog" / ("three_level" + std::to_string(level) + ".rawlog")).string(), o);
		for (int i = 0; i < 3; i++) w.write(keygrid::core::makeRgbdObservation(tinyFrame(i)));
		w.close();
	}

	const auto f = tinyFrame(0);
	cv::Mat rgba, depth16(30, 40, CV_16UC1), depth8(30, 40, CV_8UC1);
	cv::cvtColor(f.colour, rgba, cv::COLOR_BGR2BGRA);
	cv::randu(depth16, 0, 65535);
	cv::randu(depth8, 0, 255);
	cv::imwrite((dir / "png" / "rgb.png").string(), f.colour);
	cv::imwrite((dir / "png" / "rgba.png").string(), rgba);
	cv::imwrite((dir / "png" / "grey.png").string(), f.grey);
	cv::imwrite((dir / "png" / "depth16.png").string(), depth16);
	cv::imwrite((dir / "png" / "depth8_fast.png").string(), depth8, {cv::IMWRITE_PNG_COMPRESSION, 1});

	writeText(dir / "tum" / "associations.txt",
		"# rgb_timestamp rgb_file depth_timestamp depth_file\n"
		"1305031102.175304 rgb/1305031102.175304.png 1305031102.160407 depth/1305031102.160407.png\n"
		"1305031102.211214 rgb/1305031102.211214.png 1305031102.226738 depth/1305031102.226738.png\n");
	writeText(dir / "tum" / "groundtruth.txt",
		"# timestamp tx ty tz qx qy qz qw\n"
		"1305031098.6659 1.3563 0.6305 1.6380 0.6132 0.5962 -0.3311 -0.3986\n"
		"1305031098.6758 1.3543 0.6306 1.6360 0.6129 0.5966 -0.3316 -0.3980\n");

	for (const char* ini : {"config/sim.ini", "config/tum_fr1.ini"})
		if (fs::exists(src / ini)) fs::copy_file(src / ini, dir / "ini" / fs::path(ini).filename(), fs::copy_options::overwrite_existing);
	writeText(dir / "ini" / "small.ini", "[tracker]\nclose_depth = 40 ; comment\n[features]\nnum_features = 1000\nuse = true\n");
	return 0;
}
