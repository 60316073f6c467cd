#include <keygrid/sfm/TrackerOptions.h>
#include <mrpt/config/CConfigFileBase.h>

#include <algorithm>
#include <stdexcept>

namespace keygrid::sfm
{
core::OptionFields TrackerOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f(34);
	f.add("min_init_features", minInitFeatures, "keypoints with valid depth needed to start the map", R::positive());
	f.add("radius_prediction", radiusPrediction, "search radius around the motion-model prediction [px at level 0]", R::positive());
	f.add("radius_local_map", radiusLocalMap, "search radius when refining against the local map [px at level 0]", R::positive());
	f.add("min_matches_prediction", minMatchesPrediction, "matches below which a wider search, then the PnP fallback, starts");
	f.add("min_inliers", minInliers, "inliers needed to call a frame tracked", R::positive());
	f.add("local_keyframes", localKeyFrames, "covisible keyframes forming the local map", R::positive());
	f.add("relocalization_candidates", relocalizationCandidates, "newest keyframes tried when lost, after the vocabulary-tree candidates", R::atLeast(0));
	f.add("relocalization_bow_candidates", relocalizationBowCandidates, "vocabulary-tree candidates tried first when lost (0: newest keyframes only)", R::atLeast(0));
	f.add("relocalization_min_inlier_ratio", relocalizationMinInlierRatio, "share of the local map in view a relocalization must match", R::inRange(0, 1));
	f.add("relocalization_share_factor", relocalizationShareFactor, "or less: this x median share of recent tracked frames; 0 = fixed", R::inRange(0, 1));
	f.add("max_frames_between_keyframes", maxFramesBetweenKeyFrames, "a new keyframe at the latest after this many frames", R::positive());
	f.add("keyframe_tracked_ratio", keyFrameTrackedRatio, "new keyframe below this share of the reference's landmarks", R::aboveUpTo(0, 1));
	f.add("keyframe_ref_min_observations", keyFrameRefMinObservations, "reference landmarks counted: seen by >= this many keyframes", R::positive());
	f.add("close_depth", closeDepth, "depth under which a point counts as close (well measured) [m]");
	f.add("min_tracked_close", minTrackedClose, "new keyframe when fewer close points than this are tracked and ...");
	f.add("min_new_close", minNewClose, "... at least this many untracked close points could become landmarks");
	f.add("min_new_landmarks_per_keyframe", minNewLandmarksPerKeyFrame, "new landmarks per keyframe: every close one, farther ones up to this total");
	f.add("anchor_min_keyframes", anchorMinKeyFrames, "anchored pose refinement on landmarks seen by >= this many keyframes; 0 = off", R::atLeast(0));
	f.add("anchor_chi2_factor", anchorChi2Factor, "drop younger matches above this x the chi-square threshold at the anchored pose", R::atLeast(1));
	f.add("anchor_min_count", anchorMinCount, "anchors needed for the anchored refinement", R::positive());
	f.add("max_descriptor_distance_orb", matcher.maxDistanceOrb, "largest ORB descriptor distance of a match [Hamming bits]");
	f.add("max_descriptor_distance_sift", matcher.maxDistanceSift, "largest SIFT descriptor distance of a match [L2]");
	f.add("match_ratio", matcher.ratio, "largest best / second-best descriptor distance ratio", R::aboveUpTo(0, 1));
	f.add("max_depth_error", matcher.maxDepthError, "largest |measured - predicted| depth of a match, relative to the depth");
	f.add("bf", pose.bf, "virtual baseline x fx for depth residuals [px m]", R::positive());
	f.add("disparity_sigma", pose.disparitySigma, "std-dev of the virtual disparity bf/depth [px]: sigma_z = this z^2/bf", R::positive());
	f.add("pose_rounds", pose.rounds, "outlier rounds of pose refinement", R::positive());
	f.add("pose_iterations", pose.iterationsPerRound, "iterations per round of pose refinement", R::positive());
	f.add("seed", pnp.seed, "random seed of the PnP RANSAC");
	f.add("rolling_shutter_readout", rollingShutterReadout, "first-to-last row exposure time [s]; 0 = global shutter", R::fromBelow(0, 1));
	return f;
}

void TrackerOptions::validate(const std::string& s) const
{
	core::validateFields(*this, s);
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
