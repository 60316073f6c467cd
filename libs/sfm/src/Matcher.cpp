#include <keygrid/core/Hamming.h>
#include <keygrid/core/NearestTwo.h>
#include <keygrid/sfm/Matcher.h>
#include <opencv2/features2d.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>
#include <limits>

namespace keygrid::sfm
{
int predictLevel(const Landmark& lm, double dist, const FrameFeatures& f)
{
	const int nLevels = f.numLevels;
	if (dist <= 0 || lm.maxDistance <= 0 || f.levelScale.size() < 2) return 0;
	const double ratio = lm.maxDistance / dist;
	const int level = static_cast<int>(std::ceil(std::log(ratio) / std::log(f.levelScale[1])));
	return std::clamp(level, 0, nLevels - 1);
}

bool projectLandmark(
	const Landmark& lm, const mrpt::poses::CPose3D& T_cam_world, const Eigen::Vector3d& center,
	const PinholeIntrinsics& K, const FrameFeatures& f, const MatcherOptions& o, ProjectedLandmark& out)
{
	double x, y, z;
	T_cam_world.composePoint(lm.p_world.x(), lm.p_world.y(), lm.p_world.z(), x, y, z);
	if (z <= 0.05) return false;
	const double u = K.fx * x / z + K.cx, v = K.fy * y / z + K.cy;
	const double margin = 2.0;
	if (u < -margin || v < -margin || u > f.camera.width + margin || v > f.camera.height + margin) return false;
	const Eigen::Vector3d ray = lm.p_world - center;
	const double dist = ray.norm();
	if (lm.maxDistance > 0 && (dist < 0.8 * lm.minDistance || dist > 1.2 * lm.maxDistance)) return false;
	if (lm.normal.squaredNorm() > 0 && ray.dot(lm.normal) < o.minViewCosine * dist) return false;
	out.id = lm.id;
	out.p_world = lm.p_world;
	out.u = static_cast<float>(u);
	out.v = static_cast<float>(v);
	out.depth = static_cast<float>(z);
	out.predictedLevel = predictLevel(lm, dist, f);
	out.descriptor = &lm.descriptor;
	return true;
}

int searchByProjection(
	const FrameFeatures& f, const std::vector<ProjectedLandmark>& cands, float radius,
	const MatcherOptions& o, std::vector<LandmarkId>& matches)
{
	const float maxDist = o.maxDistance(f.isBinary());
	int added = 0;
	std::vector<int> idx;
	for (const auto& c : cands)
	{
		const float r = radius * static_cast<float>(f.levelScale.empty() ? 1.0 : f.levelScale[c.predictedLevel]);
		f.featuresInArea(c.u, c.v, r, std::max(0, c.predictedLevel - 1), c.predictedLevel + 1, idx);
		float best = 1e30f, second = 1e30f;
		int bestIdx = -1, bestLevel = -1, secondLevel = -1;
		for (int i : idx)
		{
			if (matches[i] != kNoLandmark) continue;
			const float d = f.depth[i];
			if (d > 0 && std::abs(d - c.depth) > o.maxDepthError * c.depth) continue;
			const float dist = descriptorDistance(*c.descriptor, 0, f.descriptors, i);
			if (dist < best)
			{
				second = best;
				secondLevel = bestLevel;
				best = dist;
				bestIdx = i;
				bestLevel = f.keypoints[i].octave;
			}
			else if (dist < second)
			{
				second = dist;
				secondLevel = f.keypoints[i].octave;
			}
		}
		if (bestIdx < 0 || best > maxDist) continue;
		if (bestLevel == secondLevel && best > o.ratio * second) continue;
		matches[bestIdx] = c.id;
		++added;
	}
	return added;
}

std::vector<std::pair<int, int>> matchBruteForce(
	const FrameFeatures& a, const FrameFeatures& b, const MatcherOptions& o, float ratio)
{
	std::vector<std::pair<int, int>> out;
	if (a.descriptors.empty() || b.descriptors.empty()) return out;
	const int norm = a.isBinary() ? cv::NORM_HAMMING : cv::NORM_L2;
	cv::BFMatcher bf(norm, false);
	std::vector<std::vector<cv::DMatch>> ab;
	std::vector<cv::DMatch> ba;
	bf.knnMatch(a.descriptors, b.descriptors, ab, 2);
	bf.match(b.descriptors, a.descriptors, ba);
	const float maxDist = o.maxDistance(a.isBinary());
	for (const auto& m : ab)
	{
		if (m.empty() || m[0].distance > maxDist) continue;
		if (m.size() > 1 && m[0].distance > ratio * m[1].distance) continue;
		if (ba[m[0].trainIdx].trainIdx != m[0].queryIdx) continue;  // mutual best
		out.emplace_back(m[0].queryIdx, m[0].trainIdx);
	}
	return out;
}

namespace
{
/** Distances of row i of `q` to every row of `table`, into out (resized): one Hamming table
 * scan for binary descriptors (core::hammingDistances, into the caller's scratch `bits`),
 * descriptorDistance otherwise. */
void rowDistances(const cv::Mat& q, int i, const cv::Mat& table, std::vector<int>& bits, std::vector<float>& out)
{
	const int n = table.rows;
	out.resize(static_cast<std::size_t>(n));
	if (q.type() == CV_8U && table.type() == CV_8U && q.cols == table.cols && q.cols % 8 == 0 && table.isContinuous())
	{
		bits.resize(static_cast<std::size_t>(n));
		core::hammingDistances(q.ptr<std::uint64_t>(i), table.ptr<std::uint64_t>(0), table.step1() / 8, n, q.cols / 8, bits.data());
		for (int j = 0; j < n; j++) out[static_cast<std::size_t>(j)] = static_cast<float>(bits[static_cast<std::size_t>(j)]);
		return;
	}
	for (int j = 0; j < n; j++) out[static_cast<std::size_t>(j)] = descriptorDistance(q, i, table, j);
}
}  // namespace

std::vector<std::pair<int, int>> matchSubsetBruteForce(
	const FrameFeatures& a, const std::vector<int>& ia, const FrameFeatures& b, float maxDist, float ratio)
{
	std::vector<std::pair<int, int>> out;
	const int na = a.descriptors.rows, nb = b.descriptors.rows;
	if (ia.empty() || nb == 0) return out;
	std::vector<float> toB, toA;
	std::vector<int> bits;
	for (int i : ia)
	{
		rowDistances(a.descriptors, i, b.descriptors, bits, toB);
		core::NearestTwo<float> nearest;
		for (int j = 0; j < nb; j++) nearest.add(toB[static_cast<std::size_t>(j)], j);
		const int best = nearest.index;
		const float d1 = nearest.best;
		if (d1 > maxDist || (nb > 1 && d1 > ratio * nearest.second)) continue;
		// Mutual best: b's keypoint has no closer keypoint in a (nor an equal one before i).
		rowDistances(b.descriptors, best, a.descriptors, bits, toA);
		bool mutual = true;
		for (int k = 0; k < na && mutual; k++)
		{
			if (k == i) continue;
			const float d = toA[static_cast<std::size_t>(k)];
			if (d < d1 || (d == d1 && k < i)) mutual = false;
		}
		if (mutual) out.emplace_back(i, best);
	}
	return out;
}

}  // namespace keygrid::sfm
