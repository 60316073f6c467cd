#pragma once
/** \file SyntheticSession.h
 * Random but realistic session records for the store's tests and benchmark: ORB-like keyframes
 * (keypoints over a 640x480 image, 32-byte descriptors, a sparse BoW vector), textured grey /
 * colour images and smooth 16-bit depth, landmarks with observations and HOC counts. Everything
 * is a function of the seed and the id, so a test can rebuild what a writer wrote.
 */
#include <keygrid/store/KeyFrameImageCodec.h>
#include <keygrid/store/SessionRecords.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <random>

namespace keygrid::test
{
/** Keyframe `id` with `numKeypoints` keypoints; every third keypoint has no landmark, the others
 * observe landmark id * 1000 + i. */
inline store::KeyFrameRecord syntheticKeyFrame(store::KeyFrameId id, int numKeypoints, std::uint64_t seed = 1)
{
	std::mt19937_64 rng(seed * 7919 + id);
	std::uniform_real_distribution<double> u(0, 1);
	store::KeyFrameRecord kf;
	kf.id = id;
	kf.frameIndex = 10 * id + 3;
	kf.timestamp = 1305031102.175304 + 0.3 * static_cast<double>(id);
	kf.T_world_cam = mrpt::poses::CPose3D(u(rng) * 4 - 2, u(rng) * 4 - 2, u(rng), u(rng) * 6 - 3, u(rng) - 0.5, u(rng) - 0.5);
	kf.hasParent = id > 0;
	kf.parent = id > 0 ? id - 1 : 0;
	kf.camera = core::RgbdCamera::Preset("fr1");
	kf.numLevels = 8;
	for (int l = 0; l < kf.numLevels; l++) kf.levelScale.push_back(std::pow(1.2, l));
	const auto n = static_cast<std::size_t>(numKeypoints);
	kf.descriptors = cv::Mat(numKeypoints, 32, CV_8U);
	if (numKeypoints > 0) cv::RNG(seed * 7919 + id).fill(kf.descriptors, cv::RNG::UNIFORM, 0, 256);
	for (std::size_t i = 0; i < n; i++)
	{
		const int octave = static_cast<int>(u(rng) * 8);
		kf.keypoints.emplace_back(static_cast<float>(u(rng) * 639), static_cast<float>(u(rng) * 479),
								  static_cast<float>(31 * kf.levelScale[static_cast<std::size_t>(octave)]),
								  static_cast<float>(u(rng) * 360), static_cast<float>(u(rng) * 1e-3), octave, -1);
		kf.undistorted.emplace_back(kf.keypoints.back().pt.x + 0.25f, kf.keypoints.back().pt.y - 0.125f);
		kf.keypointDepth.push_back(i % 5 == 0 ? 0.f : static_cast<float>(0.5 + 3 * u(rng)));
		kf.landmarks.push_back(i % 3 == 0 ? store::kNoLandmark : id * 1000 + i);
	}
	std::vector<loop::WordId> words;
	for (int i = 0; i < 400; i++) words.push_back(static_cast<loop::WordId>(u(rng) * 10000));
	std::sort(words.begin(), words.end());
	words.erase(std::unique(words.begin(), words.end()), words.end());
	for (const auto w : words) kf.bow.push_back({w, u(rng) / static_cast<double>(words.size())});
	return kf;
}

/** A 640x480 textured colour (CV_8UC3) or grey image: random rectangles and circles, so it
 * compresses like a real image, not like noise or a flat colour. */
inline cv::Mat syntheticImage(std::uint64_t seed, bool colour, int width = 640, int height = 480)
{
	std::mt19937_64 rng(seed);
	std::uniform_int_distribution<int> x(0, width - 1), y(0, height - 1), r(3, 60), g(0, 255);
	cv::Mat img(height, width, colour ? CV_8UC3 : CV_8UC1, cv::Scalar::all(128));
	for (int i = 0; i < 300; i++)
	{
		const cv::Scalar c(g(rng), g(rng), g(rng));
		if (i % 2) cv::rectangle(img, cv::Rect(x(rng), y(rng), r(rng), r(rng)), c, cv::FILLED);
		else cv::circle(img, cv::Point(x(rng), y(rng)), r(rng), c, cv::FILLED);
	}
	cv::Mat noise(img.size(), img.type());
	cv::RNG(seed).fill(noise, cv::RNG::UNIFORM, 0, 7);
	return img + noise - cv::Scalar::all(3);
}

/** Smooth depth (a tilted plane plus boxes) in raw units at 0.2 mm, with invalid (0) holes. */
inline cv::Mat syntheticDepthRaw(std::uint64_t seed, int width = 640, int height = 480)
{
	std::mt19937_64 rng(seed);
	std::uniform_int_distribution<int> x(0, width - 1), y(0, height - 1), r(5, 80), d(3000, 20000);
	cv::Mat depth(height, width, CV_16UC1);
	for (int v = 0; v < height; v++)
		for (int c = 0; c < width; c++) depth.at<std::uint16_t>(v, c) = static_cast<std::uint16_t>(8000 + 10 * v + 3 * c);
	for (int i = 0; i < 30; i++) cv::rectangle(depth, cv::Rect(x(rng), y(rng), r(rng), r(rng)), cv::Scalar(d(rng)), cv::FILLED);
	for (int i = 0; i < 20; i++) cv::circle(depth, cv::Point(x(rng), y(rng)), r(rng) / 4, cv::Scalar(0), cv::FILLED);
	return depth;
}

/** Landmark `id` observed by keyframes first..first+numObs-1. */
inline store::LandmarkRecord syntheticLandmark(store::LandmarkId id, store::KeyFrameId first, int numObs, std::uint64_t seed = 1)
{
	std::mt19937_64 rng(seed * 104729 + id);
	std::uniform_real_distribution<double> u(0, 1);
	store::LandmarkRecord lm;
	lm.id = id;
	lm.p_world = {u(rng) * 10 - 5, u(rng) * 10 - 5, u(rng) * 3};
	lm.normal = Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, u(rng) + 0.1).normalized();
	lm.minDistance = 0.5 + u(rng);
	lm.maxDistance = lm.minDistance * 7.5;
	lm.firstKeyFrame = first;
	lm.visibleCount = 3 + static_cast<int>(u(rng) * 50);
	lm.foundCount = 1 + lm.visibleCount / 2;
	lm.descriptor = cv::Mat(1, 32, CV_8U);
	cv::RNG(seed * 104729 + id).fill(lm.descriptor, cv::RNG::UNIFORM, 0, 256);
	for (int k = 0; k < numObs; k++) lm.observations[first + static_cast<store::KeyFrameId>(k)] = static_cast<int>(u(rng) * 1000);
	if (id % 2 == 0)
		for (int b = 0; b < 60; b++) lm.hocCounts.push_back(static_cast<std::int16_t>(static_cast<int>(u(rng) * 41) - 20));
	return lm;
}

}  // namespace keygrid::test
