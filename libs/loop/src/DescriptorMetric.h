#pragma once
/** \file DescriptorMetric.h (private)
 * Distances and cluster centres of the two descriptor families the vocabulary supports:
 * - BinaryMetric: rows of CV_8U bits (ORB: 32 bytes), Hamming distance, bit-majority centres;
 * - FloatMetric:  rows of CV_32F (SIFT: 128 floats), squared Euclidean distance, mean centres.
 * Both give "distance" values whose ordering is what k-means and the tree descent need;
 * k-means++ seeding uses distance^2 for Hamming and the squared L2 itself for floats.
 */
#include <keygrid/core/Hamming.h>
#include <opencv2/core.hpp>

#include <cstdint>
#include <cstring>
#include <vector>

namespace keygrid::loop::detail
{
struct BinaryMetric
{
	int cols;  //!< bytes per descriptor

	double distance(const uchar* a, const uchar* b) const
	{
		int d = 0, i = 0;
		for (; i + 8 <= cols; i += 8)
		{
			std::uint64_t x, y;
			std::memcpy(&x, a + i, 8);
			std::memcpy(&y, b + i, 8);
			d += core::popcount64(x ^ y);
		}
		for (; i < cols; ++i) d += core::popcount64(static_cast<std::uint64_t>(a[i] ^ b[i]));
		return d;
	}
	/** Weight of k-means++ seeding: D(x)^2. */
	double seedingWeight(double d) const { return d * d; }

	/** Bit-majority centre of the rows `members` of `data`: a bit is set when more than half of
	 * the members have it set. */
	void centre(const cv::Mat& data, const int* members, std::size_t n, uchar* out) const
	{
		std::vector<int> ones(static_cast<std::size_t>(cols) * 8, 0);
		for (std::size_t m = 0; m < n; ++m)
		{
			const uchar* row = data.ptr<uchar>(members[m]);
			for (int byte = 0; byte < cols; ++byte)
			{
				const uchar v = row[byte];
				if (!v) continue;
				int* o = &ones[static_cast<std::size_t>(byte) * 8];
				for (int bit = 0; bit < 8; ++bit) o[bit] += (v >> (7 - bit)) & 1;
			}
		}
		for (int byte = 0; byte < cols; ++byte)
		{
			uchar v = 0;
			for (int bit = 0; bit < 8; ++bit)
				if (2 * static_cast<std::size_t>(ones[static_cast<std::size_t>(byte) * 8 + bit]) > n)
					v |= static_cast<uchar>(1u << (7 - bit));
			out[byte] = v;
		}
	}
};

struct FloatMetric
{
	int cols;  //!< floats per descriptor

	double distance(const uchar* a8, const uchar* b8) const
	{
		const float* a = reinterpret_cast<const float*>(a8);
		const float* b = reinterpret_cast<const float*>(b8);
		float d = 0;
		for (int i = 0; i < cols; ++i)
		{
			const float e = a[i] - b[i];
			d += e * e;
		}
		return d;
	}
	/** Weight of k-means++ seeding: D(x)^2 (distance() already is squared). */
	double seedingWeight(double d) const { return d; }

	void centre(const cv::Mat& data, const int* members, std::size_t n, uchar* out8) const
	{
		std::vector<double> sum(static_cast<std::size_t>(cols), 0.0);
		for (std::size_t m = 0; m < n; ++m)
		{
			const float* row = data.ptr<float>(members[m]);
			for (int i = 0; i < cols; ++i) sum[static_cast<std::size_t>(i)] += row[i];
		}
		float* out = reinterpret_cast<float*>(out8);
		for (int i = 0; i < cols; ++i)
			out[i] = n ? static_cast<float>(sum[static_cast<std::size_t>(i)] / static_cast<double>(n)) : 0.f;
	}
};

}  // namespace keygrid::loop::detail
