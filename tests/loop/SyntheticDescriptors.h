#pragma once
/** \file SyntheticDescriptors.h
 * Descriptor sets with known structure for the loop tests: clusters around random centres
 * (binary: bit flips, float: Gaussian noise) and "images" drawn from a pool of prototypes.
 */
#include <keygrid/loop/Vocabulary.h>
#include <opencv2/core.hpp>

#include <cstdint>
#include <random>
#include <vector>

namespace keygrid::test
{
inline cv::Mat randomBinary(int rows, int bytes, std::mt19937_64& rng)
{
	cv::Mat m(rows, bytes, CV_8U);
	std::uniform_int_distribution<int> byte(0, 255);
	for (int r = 0; r < rows; ++r)
		for (int c = 0; c < bytes; ++c) m.at<uchar>(r, c) = static_cast<uchar>(byte(rng));
	return m;
}

/** A vocabulary (`branching` x `levels`, other options default) trained on `images` "images" of
 * `rows` random binary descriptors each, drawn from `rng`. */
inline loop::Vocabulary randomBinaryVocabulary(int images, int rows, int branching, int levels, std::mt19937_64& rng)
{
	std::vector<cv::Mat> imgs;
	for (int i = 0; i < images; ++i) imgs.push_back(randomBinary(rows, 32, rng));
	loop::VocabularyOptions o;
	o.branching = branching;
	o.levels = levels;
	return loop::Vocabulary::train(imgs, o);
}

/** Copy of `d` with `flips` random bits flipped per row. */
inline cv::Mat flipBits(const cv::Mat& d, int flips, std::mt19937_64& rng)
{
	cv::Mat out = d.clone();
	std::uniform_int_distribution<int> bit(0, d.cols * 8 - 1);
	for (int r = 0; r < d.rows; ++r)
		for (int f = 0; f < flips; ++f)
		{
			const int b = bit(rng);
			out.at<uchar>(r, b / 8) ^= static_cast<uchar>(1u << (b % 8));
		}
	return out;
}

/** Float descriptors: Gaussian noise of sigma added to `d`. */
inline cv::Mat addNoise(const cv::Mat& d, float sigma, std::mt19937_64& rng)
{
	cv::Mat out = d.clone();
	std::normal_distribution<float> n(0.f, sigma);
	for (int r = 0; r < d.rows; ++r)
		for (int c = 0; c < d.cols; ++c) out.at<float>(r, c) += n(rng);
	return out;
}

/** An "image": `count` descriptors, each a prototype (row of `pool`) with `flips` bit flips. */
inline cv::Mat sampleImage(const cv::Mat& pool, int count, int flips, std::mt19937_64& rng, std::vector<int>* picked = nullptr)
{
	std::uniform_int_distribution<int> pick(0, pool.rows - 1);
	cv::Mat img(count, pool.cols, pool.type());
	for (int i = 0; i < count; ++i)
	{
		const int p = pick(rng);
		if (picked) picked->push_back(p);
		pool.row(p).copyTo(img.row(i));
	}
	return flipBits(img, flips, rng);
}

}  // namespace keygrid::test
