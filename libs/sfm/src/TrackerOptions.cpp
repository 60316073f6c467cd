#include <keygrid/sfm/TrackerOptions.h>
#include <mrpt/config/CConfigFileBase.h>

#include <algorithm>
#include <stdexcept>

namespace keygrid::sfm
{
namespace
{
template <typename T>
void positive(const std::string& s, const char* key, T v)
{
	if (!(v > 0)) throw std::invalid_argument("[" + s + "] " + key + " = " + std::to_string(v) + " (must be > 0)");
}
}  // namespace

void TrackerOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	minInitFeatures = c.read_int(s, "min_init_features", minInitFeatures);
	radiusPrediction = c.read_float(s, "radius_prediction", radiusPrediction);
	radiusLocalMap = c.read_float(s, "radius_local_map", radiusLocalMap);
	minMatchesPrediction = c.read_int(s, "min_matches_prediction", minMatchesPrediction);
	minInliers = c.read_int(s, "min_inliers", minInliers);
	localKeyFrames = c.read_int(s, "local_keyframes", localKeyFrames);
	relocalizationCandidates = c.read_int(s, "relocalization_candidates", relocalizationCandidates);
	relocalizationBowCandidates = c.read_int(s, "relocalization_bow_candidates", relocalizationBowCandidates);
	relocalizationMinInlierRatio = c.read_double(s, "relocalization_min_inlier_ratio", relocalizationMinInlierRatio);
	relocalizationShareFactor = c.read_double(s, "relocalization_share_factor", relocalizationShareFactor);
	maxFramesBetweenKeyFrames = c.read_int(s, "max_frames_between_keyframes", maxFramesBetweenKeyFrames);
	keyFrameTrackedRatio = c.read_double(s, "keyframe_tracked_ratio", keyFrameTrackedRatio);
	keyFrameRefMinObservations = c.read_int(s, "keyframe_ref_min_observations", keyFrameRefMinObservations);
	closeDepth = c.read_double(s, "close_depth", closeDepth);
	minTrackedClose = c.read_int(s, "min_tracked_close", minTrackedClose);
	minNewClose = c.read_int(s, "min_new_close", minNewClose);
	minNewLandmarksPerKeyFrame = c.read_int(s, "min_new_landmarks_per_keyframe", minNewLandmarksPerKeyFrame);
	anchorMinKeyFrames = c.read_int(s, "anchor_min_keyframes", anchorMinKeyFrames);
	anchorChi2Factor = c.read_double(s, "anchor_chi2_factor", anchorChi2Factor);
	anchorMinCount = c.read_int(s, "anchor_min_count", anchorMinCount);
	matcher.maxDistanceOrb = c.read_float(s, "max_descriptor_distance_orb", matcher.maxDistanceOrb);
	matcher.maxDistanceSift = c.read_float(s, "max_descriptor_distance_sift", matcher.maxDistanceSift);
	matcher.ratio = c.read_float(s, "match_ratio", matcher.ratio);
	matcher.maxDepthError = c.read_float(s, "max_depth_error", matcher.maxDepthError);
	pose.bf = c.read_double(s, "bf", pose.bf);
	pose.disparitySigma = c.read_double(s, "disparity_sigma", pose.disparitySigma);
	pose.rounds = c.read_int(s, "pose_rounds", pose.rounds);
	pose.iterationsPerRound = c.read_int(s, "pose_iterations", pose.iterationsPerRound);
	pnp.seed = static_cast<uint64_t>(c.read_uint64_t(s, "seed", pnp.seed));
	rollingShutterReadout = c.read_double(s, "rolling_shutter_readout", rollingShutterReadout);
	if (!(rollingShutterReadout >= 0 && rollingShutterReadout < 1))
		throw std::invalid_argument("[" + s + "] rolling_shutter_readout = " + std::to_string(rollingShutterReadout) + " s (must be in [0, 1))");
	positive(s, "min_init_features", minInitFeatures);
	positive(s, "radius_prediction", radiusPrediction);
	positive(s, "radius_local_map", radiusLocalMap);
	positive(s, "min_inliers", minInliers);
	positive(s, "local_keyframes", localKeyFrames);
	positive(s, "max_frames_between_keyframes", maxFramesBetweenKeyFrames);
	positive(s, "bf", pose.bf);
	positive(s, "disparity_sigma", pose.disparitySigma);
	positive(s, "keyframe_ref_min_observations", keyFrameRefMinObservations);
	positive(s, "pose_rounds", pose.rounds);
	positive(s, "pose_iterations", pose.iterationsPerRound);
	if (anchorMinKeyFrames < 0) throw std::invalid_argument("[" + s + "] anchor_min_keyframes = " + std::to_string(anchorMinKeyFrames) + " (must be >= 0; 0 = off)");
	if (!(anchorChi2Factor >= 1))
		throw std::invalid_argument("[" + s + "] anchor_chi2_factor = " + std::to_string(anchorChi2Factor) + " (must be >= 1)");
	positive(s, "anchor_min_count", anchorMinCount);
	if (relocalizationCandidates < 0 || relocalizationBowCandidates < 0)
		throw std::invalid_argument("[" + s + "] relocalization_candidates / relocalization_bow_candidates must be >= 0");
	if (!(relocalizationMinInlierRatio >= 0 && relocalizationMinInlierRatio <= 1))
		throw std::invalid_argument("[" + s + "] relocalization_min_inlier_ratio = " + std::to_string(relocalizationMinInlierRatio) + " (must be in [0, 1])");
	if (!(relocalizationShareFactor >= 0 && relocalizationShareFactor <= 1))
		throw std::invalid_argument("[" + s + "] relocalization_share_factor = " + std::to_string(relocalizationShareFactor) + " (must be in [0, 1])");
	if (!(keyFrameTrackedRatio > 0 && keyFrameTrackedRatio <= 1))
		throw std::invalid_argument("[" + s + "] keyframe_tracked_ratio = " + std::to_string(keyFrameTrackedRatio) + " (must be in (0, 1])");
	if (!(matcher.ratio > 0 && matcher.ratio <= 1))
		throw std::invalid_argument("[" + s + "] match_ratio = " + std::to_string(matcher.ratio) + " (must be in (0, 1])");
}

void TrackerOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	c.write(s, "min_init_features", minInitFeatures, 34, 40, "keypoints with depth needed to start the map");
	c.write(s, "radius_prediction", radiusPrediction, 34, 40, "search radius at the predicted pose [px]");
	c.write(s, "radius_local_map", radiusLocalMap, 34, 40, "search radius when refining [px]");
	c.write(s, "min_matches_prediction", minMatchesPrediction, 34, 40, "below: wider search, then PnP fallback");
	c.write(s, "min_inliers", minInliers, 34, 40, "inliers to call a frame tracked");
	c.write(s, "local_keyframes", localKeyFrames, 34, 40, "keyframes forming the local map");
	c.write(s, "relocalization_candidates", relocalizationCandidates, 34, 40, "newest keyframes tried when lost");
	c.write(s, "relocalization_bow_candidates", relocalizationBowCandidates, 34, 40, "vocabulary-tree candidates tried first when lost");
	c.write(s, "relocalization_min_inlier_ratio", relocalizationMinInlierRatio, 34, 40, "share of the local map in view a relocalization must match");
	c.write(s, "relocalization_share_factor", relocalizationShareFactor, 34, 40, "or less: this x median share of recent tracked frames; 0 = fixed");
	c.write(s, "max_frames_between_keyframes", maxFramesBetweenKeyFrames, 34, 40, "");
	c.write(s, "keyframe_tracked_ratio", keyFrameTrackedRatio, 34, 40, "new keyframe below this share of the reference's landmarks");
	c.write(s, "keyframe_ref_min_observations", keyFrameRefMinObservations, 34, 40, "reference landmarks counted: seen by >= this many keyframes");
	c.write(s, "close_depth", closeDepth, 34, 40, "[m]");
	c.write(s, "min_tracked_close", minTrackedClose, 34, 40, "");
	c.write(s, "min_new_close", minNewClose, 34, 40, "");
	c.write(s, "min_new_landmarks_per_keyframe", minNewLandmarksPerKeyFrame, 34, 40, "");
	c.write(s, "anchor_min_keyframes", anchorMinKeyFrames, 34, 40, "anchored pose refinement on landmarks seen by >= this many keyframes; 0 = off");
	c.write(s, "anchor_chi2_factor", anchorChi2Factor, 34, 40, "drop younger matches above this x the chi-square threshold at the anchored pose");
	c.write(s, "anchor_min_count", anchorMinCount, 34, 40, "anchors needed for the anchored refinement");
	c.write(s, "max_descriptor_distance_orb", matcher.maxDistanceOrb, 34, 40, "Hamming bits");
	c.write(s, "max_descriptor_distance_sift", matcher.maxDistanceSift, 34, 40, "L2");
	c.write(s, "match_ratio", matcher.ratio, 34, 40, "best/second-best");
	c.write(s, "max_depth_error", matcher.maxDepthError, 34, 40, "|measured-predicted| depth / depth");
	c.write(s, "bf", pose.bf, 34, 40, "virtual baseline x fx for depth residuals [px m]");
	c.write(s, "disparity_sigma", pose.disparitySigma, 34, 40, "std-dev of the virtual disparity bf/depth [px]: sigma_z = this z^2/bf");
	c.write(s, "pose_rounds", pose.rounds, 34, 40, "outlier rounds of pose refinement");
	c.write(s, "pose_iterations", pose.iterationsPerRound, 34, 40, "iterations per round");
	c.write(s, "seed", pnp.seed, 34, 40, "RANSAC seed");
	c.write(s, "rolling_shutter_readout", rollingShutterReadout, 34, 40, "first-to-last row exposure time [s]; 0 = global shutter");
}

double medianShare(std::vector<double> shares)
{
	if (shares.empty()) throw std::invalid_argument("medianShare: no shares");
	auto mid = shares.begin() + static_cast<std::ptrdiff_t>(shares.size() / 2);
	std::nth_element(shares.begin(), mid, shares.end());
	return *mid;
}

double requiredRelocalizationShare(const TrackerOptions& o, std::vector<double> recent)
{
	if (o.relocalizationShareFactor <= 0 || recent.empty()) return o.relocalizationMinInlierRatio;
	return std::min(o.relocalizationMinInlierRatio, o.relocalizationShareFactor * medianShare(std::move(recent)));
}

}  // namespace keygrid::sfm
