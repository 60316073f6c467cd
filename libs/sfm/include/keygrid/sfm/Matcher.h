#pragma once
/** \file Matcher.h
 * Descriptor matching: landmarks projected into a frame (guided search in a window), and
 * brute-force matching between two keypoint sets (for the PnP fallback and relocalization).
 */
#include <keygrid/sfm/FrameFeatures.h>
#include <keygrid/sfm/RgbdReprojectionCost.h>
#include <keygrid/sfm/SparseMap.h>

#include <vector>

namespace keygrid::sfm
{
struct MatcherOptions
{
	/** Largest descriptor distance for a match: Hamming bits for ORB (Default: 80) */
	float maxDistanceOrb{80};
	/** Largest L2 distance for SIFT descriptors (Default: 250) */
	float maxDistanceSift{250};
	/** Best / second-best ratio within the search window (Default: 0.85) */
	float ratio{0.85f};
	/** Largest |measured depth - predicted depth| as a fraction of depth (Default: 0.1) */
	float maxDepthError{0.1f};
	/** Smallest cosine between viewing ray and landmark normal (Default: 0.5, i.e. 60 deg) */
	double minViewCosine{0.5};

	float maxDistance(bool binary) const { return binary ? maxDistanceOrb : maxDistanceSift; }
};

/** A landmark predicted inside the current image. */
struct ProjectedLandmark
{
	LandmarkId id{kNoLandmark};
	Eigen::Vector3d p_world;
	float u{0}, v{0}, depth{0};
	int predictedLevel{0};
	const cv::Mat* descriptor{nullptr};
};

/** Projects a landmark into a camera; false when behind, outside the image (with margin),
 * outside its scale-invariance distance, or seen too obliquely. */
bool projectLandmark(
	const Landmark& lm, const mrpt::poses::CPose3D& T_cam_world, const Eigen::Vector3d& camCenter,
	const PinholeIntrinsics& K, const FrameFeatures& f, const MatcherOptions& o, ProjectedLandmark& out);

/** For each projected landmark, searches keypoints within radius * scale(predictedLevel) of
 * its prediction (levels predicted-1..predicted+1) and keeps the best if distinct enough.
 * `matches[kp]` receives the landmark id; keypoints already matched are skipped.
 * Returns the number of new matches. */
int searchByProjection(
	const FrameFeatures& f, const std::vector<ProjectedLandmark>& candidates, float radius,
	const MatcherOptions& o, std::vector<LandmarkId>& matches);

/** Mutual nearest-neighbour descriptor matches between a and b passing the ratio test
 * (pairs (index in a, index in b)). */
std::vector<std::pair<int, int>> matchBruteForce(
	const FrameFeatures& a, const FrameFeatures& b, const MatcherOptions& o, float ratio = 0.8f);

/** The matches of matchBruteForce(a, b, ratio) (mutual nearest neighbours over all keypoints of
 * both sets, distance <= maxDist, best / second-best ratio) whose keypoint in a is one of `ia`,
 * without the full |a| x |b| distance table: each row of `ia` is scanned against all of b and
 * only its best match is checked for mutuality against all of a. Ties go to the lower index,
 * as in OpenCV's brute-force matcher. Used for triangulation, where only the few keypoints of
 * the new keyframe without landmark and depth are candidates: O(|ia| |b| + |matches| |a|). */
std::vector<std::pair<int, int>> matchSubsetBruteForce(
	const FrameFeatures& a, const std::vector<int>& ia, const FrameFeatures& b, float maxDist, float ratio);

/** Predicted pyramid level of a landmark seen at distance `dist`. */
int predictLevel(const Landmark& lm, double dist, const FrameFeatures& f);

}  // namespace keygrid::sfm
