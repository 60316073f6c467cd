#pragma once
/** \file TrackerOptions.h
 * Parameters of frame tracking and keyframe selection.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>
#include <keygrid/maps/HocHistogram.h>
#include <keygrid/sfm/Matcher.h>
#include <keygrid/sfm/MonocularOptions.h>
#include <keygrid/sfm/PnpSolver.h>
#include <keygrid/sfm/PoseOptimizer.h>

#include <string>
#include <vector>

namespace keygrid::sfm
{
struct TrackerOptions : public core::FieldTableOptions<TrackerOptions>
{
	/** Keypoints with valid depth needed to initialise the map (Default: 300) */
	int minInitFeatures{300};
	/** Search radius around the motion-model prediction [px at level 0] (Default: 12) */
	float radiusPrediction{12.f};
	/** Search radius when refining against the local map [px at level 0] (Default: 4) */
	float radiusLocalMap{4.f};
	/** Matches below which the wide search / PnP fallback starts (Default: 30) */
	int minMatchesPrediction{30};
	/** Inliers needed to call a frame tracked (Default: 25) */
	int minInliers{25};
	/** Covisible keyframes forming the local map (Default: 20) */
	int localKeyFrames{20};
	/** Keyframes tried (newest first) when relocalizing, after the place-recognition
	 * candidates (Default: 20) */
	int relocalizationCandidates{20};
	/** Place-recognition candidates (vocabulary tree, see Tracker::setPlaceRecognizer) tried
	 * first when relocalizing; 0 = newest keyframes only (Default: 10) */
	int relocalizationBowCandidates{10};
	/** A relocalization holds only when the local-map search matches at least this share of
	 * the local map's landmarks in view: a true revisit matches a good share of them, a
	 * look-alike place (periodic texture) only a few (Default: 0.25) */
	double relocalizationMinInlierRatio{0.25};
	/** Adapts that share to the features and the data: the required share is
	 * min(relocalization_min_inlier_ratio, this x the median share matched by the last 30
	 * tracked frames): where even normal tracking matches a small share (real sequences, SIFT),
	 * a true place matching less than the fixed share is still accepted. 0 = the fixed share
	 * (Default: 0.6) */
	double relocalizationShareFactor{0.6};

	/** A keyframe at the latest after this many frames (Default: 30) */
	int maxFramesBetweenKeyFrames{30};
	/** Insert when tracked landmarks fall below this fraction of the reference keyframe's (Default: 0.5) */
	double keyFrameTrackedRatio{0.5};
	/** Reference-keyframe landmarks counted by that ratio: those seen by at least this many
	 * keyframes (Default: 1, all of them. ORB-SLAM2's RGB-D rule, 2 with ratio 0.75, makes
	 * fewer keyframes and larger errors: doc/evaluation-history.md) */
	int keyFrameRefMinObservations{1};
	/** Depth under which points count as "close" (well-measured) [m] (Default: 3.0) */
	double closeDepth{3.0};
	/** Insert when fewer close points are tracked than this and ... (Default: 100) */
	int minTrackedClose{100};
	/** ... at least this many untracked close points could become landmarks (Default: 70) */
	int minNewClose{70};
	/** New landmarks per keyframe: all close ones, and farther ones up to this total (Default: 100) */
	int minNewLandmarksPerKeyFrame{100};

	/** Rolling shutter: time between the exposure of the first and the last image row [s];
	 * keypoints are moved to the frame's timestamp with the camera's estimated motion
	 * (RollingShutter.h). 0 = global shutter (Default: 0; the shipped Kinect configurations
	 * set the value calibrated on TUM fr1, doc/frontend.md "Rolling shutter") */
	double rollingShutterReadout{0.0};

	/** Anchored pose refinement against moving objects (optimizePoseAnchored, PoseOptimizer.h):
	 * the final refinement of each frame is solved first from the landmarks seen by at least
	 * this many keyframes, and matches of younger landmarks whose chi-square there exceeds
	 * anchor_chi2_factor x the inlier threshold are dropped, so that people walking past a
	 * moving camera do not drag it along (doc/evaluation.md). 0 = off (Default: 3) */
	int anchorMinKeyFrames{3};
	/** Rejection threshold of that test, a multiple of the chi-square inlier threshold
	 * (Default: 9, i.e. 3x the residual) */
	double anchorChi2Factor{9.0};
	/** Anchored refinement only with at least this many anchors matched; fewer (fast turns
	 * into new parts of the scene) leave the plain refinement. High enough that a few anchors
	 * on an object that stood still and then moves cannot outvote the young static points
	 * (Default: 100) */
	int anchorMinCount{100};
	/** A camera without depth: the map starts from two views and keyframes follow the
	 * monocular rule (Tracker.h; options in `monocular`). Set by the application from
	 * [slam] sensor, not a [tracker] key (Default: false) */
	bool monocular{false};
	/** The monocular mode's options ([monocular] section, loaded by the application). */
	MonocularOptions mono;
	MatcherOptions matcher;
	PoseOptimizerOptions pose;
	PnpOptions pnp;
	/** Histograms of Oriented Cameras: point selection and pruning ([hoc] section, loaded by
	 * the application; see HocFrontend.h). */
	maps::HocOptions hoc;

	/** The [tracker] keys (without [hoc] and [monocular], which are sections of their own). */
	core::OptionFields fields();
	/** Throws std::invalid_argument naming section, key, value and rule of an invalid option. */
	void validate(const std::string& section = "tracker") const;
};

/** Share of the local map in view that a relocalization must match: min(o.relocalizationMinInlierRatio,
 * o.relocalizationShareFactor x the median of `recentShares`), the shares matched by recently
 * tracked frames (the fixed ratio when the factor is 0 or there are none). */
double requiredRelocalizationShare(const TrackerOptions& o, std::vector<double> recentShares);
/** The median of tracked frames' shares of the local map (the upper one of an even count);
 * throws std::invalid_argument when empty. */
double medianShare(std::vector<double> shares);

}  // namespace keygrid::sfm
