/** \file dynamic_feature_share.cpp
 * Share of the frontend's features (with valid depth, i.e. those that can become map points)
 * that lie on dynamic objects, from the per-frame masks keygrid-sim writes into tum/mask/.
 * Usage: keygrid_dynamic_feature_share TUM_DIR [orb|sift] [num_features]
 * Prints: frames, features, on dynamic objects, share (mean over frames and peak frame).
 */
#include <keygrid/core/TumFrameSource.h>
#include <keygrid/sfm/FeatureExtractor.h>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <string>

int main(int argc, char** argv)
{
	if (argc < 2)
	{
		std::fprintf(stderr, "usage: %s TUM_DIR [orb|sift] [num_features]\n", argv[0]);
		return 2;
	}
	try
	{
		const std::string dir = argv[1];
		keygrid::sfm::FeatureOptions o;
		if (argc > 2) o.type = argv[2];
		if (argc > 3) o.numFeatures = std::stoi(argv[3]);
		const keygrid::sfm::FeatureExtractor ex(o);
		keygrid::core::TumFrameSource src(dir);
		keygrid::core::Frame f;
		std::size_t frames = 0, total = 0, dynamic = 0;
		double peak = 0;
		while (src.next(f))
		{
			char name[64];
			std::snprintf(name, sizeof(name), "%.6f.png", f.timestamp);
			const cv::Mat mask = cv::imread(dir + "/mask/" + name, cv::IMREAD_GRAYSCALE);
			if (mask.empty()) throw std::runtime_error("no mask " + dir + "/mask/" + name + " (generate with keygrid-sim --mask)");
			const auto feats = ex.extract(f);
			std::size_t n = 0, d = 0;
			for (std::size_t i = 0; i < feats.size(); i++)
			{
				if (!(feats.depth[i] > 0)) continue;
				n++;
				const auto& kp = feats.keypoints[i].pt;
				const int x = std::clamp(static_cast<int>(kp.x + 0.5f), 0, mask.cols - 1), y = std::clamp(static_cast<int>(kp.y + 0.5f), 0, mask.rows - 1);
				d += mask.at<uint8_t>(y, x) > 0;
			}
			frames++;
			total += n;
			dynamic += d;
			if (n) peak = std::max(peak, static_cast<double>(d) / n);
		}
		std::printf("frames %zu, features with depth %zu, on dynamic objects %zu, share %.1f %% (peak frame %.1f %%)\n", frames, total, dynamic,
					100.0 * dynamic / std::max<std::size_t>(1, total), 100 * peak);
		return 0;
	}
	catch (const std::exception& e)
	{
		std::fprintf(stderr, "error: %s\n", e.what());
		return 1;
	}
}
