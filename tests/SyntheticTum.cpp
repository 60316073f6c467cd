#include "SyntheticTum.h"

#include <mrpt/system/filesystem.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace keygrid::test
{
SyntheticTum writeSyntheticTum(
	const std::string& dir, int n, int w, int h, bool withAssociations, double depthLag, unsigned seed)
{
	SyntheticTum s;
	s.dir = dir;
	mrpt::system::createDirectory(dir);
	mrpt::system::createDirectory(dir + "/rgb");
	mrpt::system::createDirectory(dir + "/depth");
	cv::RNG rng(seed);
	std::ofstream rgbTxt(dir + "/rgb.txt"), depthTxt(dir + "/depth.txt");
	rgbTxt << "# color images\n# file: 'synthetic'\n# timestamp filename\n";
	depthTxt << "# depth maps\n# file: 'synthetic'\n# timestamp filename\n";
	std::ofstream assoc;
	if (withAssociations) assoc.open(dir + "/associations.txt");
	for (int i = 0; i < n; i++)
	{
		const double tr = 1305031453.0 + i / 30.0, td = tr + depthLag;
		cv::Mat c(h, w, CV_8UC3), d(h, w, CV_16UC1);
		rng.fill(c, cv::RNG::UNIFORM, 0, 256);
		rng.fill(d, cv::RNG::UNIFORM, 0, 65536);
		d.at<uint16_t>(0, 0) = 0;  // invalid pixel
		d.at<uint16_t>(0, 1) = 65535;  // deepest representable value
		char rn[64], dn[64];
		std::snprintf(rn, sizeof(rn), "rgb/%.6f.png", tr);
		std::snprintf(dn, sizeof(dn), "depth/%.6f.png", td);
		if (!cv::imwrite(dir + "/" + rn, c) || !cv::imwrite(dir + "/" + dn, d))
			throw std::runtime_error("cannot write synthetic TUM images in " + dir);
		char line[256];
		std::snprintf(line, sizeof(line), "%.6f %s\n", tr, rn);
		rgbTxt << line;
		std::snprintf(line, sizeof(line), "%.6f %s\n", td, dn);
		depthTxt << line;
		if (withAssociations)
		{
			std::snprintf(line, sizeof(line), "%.6f %s %.6f %s\n", tr, rn, td, dn);
			assoc << line;
		}
		s.tRgb.push_back(tr);
		s.tDepth.push_back(td);
		s.colour.push_back(c);
		s.depthRaw.push_back(d);
	}
	return s;
}

}  // namespace keygrid::test
