#pragma once
/** \file MonocularOptions.h
 * Parameters of the monocular mode's tracker: the map start from two views (reference frame,
 * matching of the following frames against it, TwoViewInitializer) and the keyframe rule of a
 * camera without depth. INI section [monocular]; the two-view model's keys are part of it.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>
#include <keygrid/sfm/LocalBundleAdjuster.h>
#include <keygrid/sfm/TwoViewInitializer.h>

#include <string>

namespace keygrid::sfm
{
struct MonocularOptions : public core::FieldTableOptions<MonocularOptions>
{
	/** A frame becomes the reference of the map start only with more keypoints than this
	 * (Default: 100, as ORB-SLAM) */
	int initMinKeypoints{100};
	/** The reference frame is replaced by the current one after this many frames without a
	 * successful two-view initialization: the view has changed too much for the reference to
	 * match it well (Default: 20) */
	int initMaxFrames{20};
	/** Search window of the matching against the reference frame: radius around the
	 * keypoint's position in the last frame it was matched in [px at level 0] (Default: 100,
	 * as ORB-SLAM) */
	float initWindowPx{100.f};
	/** Largest ORB descriptor distance of such a match [Hamming bits] (Default: 50, ORB-SLAM's
	 * TH_LOW) */
	float initMaxDistanceOrb{50.f};
	/** Largest SIFT descriptor distance of such a match [L2] (Default: 200) */
	float initMaxDistanceSift{200.f};
	/** Best / second-best distance ratio of such a match (Default: 0.9, as ORB-SLAM) */
	float initRatio{0.9f};
	/** Keep only matches whose keypoint orientation change is among the three most frequent
	 * (30 bins), ORB-SLAM's rotation consistency check (Default: true) */
	bool initCheckOrientation{true};
	/** A plane seen from the reference: the homography's motions stay ambiguous whatever the
	 * parallax. Each implies a plane; the true one is the same from every current frame, the
	 * other turns with the direction of travel. A later ambiguous frame takes the motion whose
	 * plane normal is within this angle of one implied by the first ambiguous frame of the same
	 * reference, when every other motion's is more than twice as far [deg]; 0 = off. Off by
	 * default: the first ambiguous frame's normals rest on little parallax, and on a camera
	 * looking down at the floor the rule picked a wrong motion (doc/frontend.md)
	 * (Default: 0) */
	double initPlaneNormalDeg{0.0};
	/** Landmarks the two-view map must keep after its bundle adjustment, else the map start
	 * is undone and retried (Default: 100, as ORB-SLAM) */
	int initMinLandmarks{100};
	/** Iterations of the bundle adjustment of the two first keyframes (Default: 20, as
	 * ORB-SLAM) */
	int initBaIterations{20};
	/** Insert a keyframe when tracked landmarks fall below this share of the reference
	 * keyframe's (ORB-SLAM2's monocular 0.9; without depth only keyframes make new landmarks,
	 * so they come more often than in RGB-D mode) (Default: 0.9) */
	double keyFrameTrackedRatio{0.9};
	/** Threaded mode with [slam] mapping_lag > 0: replaces [slam] busy_keyframe_ratio in
	 * monocular mode. While local mapping is still working on a keyframe, tracking inserts a
	 * new one only below this share of the reference keyframe's landmarks (or at the keyframe
	 * timeout). Higher than the RGB-D share: a monocular frame brings no landmarks of its own,
	 * only keyframes do (once local mapping has triangulated them), so deferring keyframes until
	 * tracking has lost most of its reference's landmarks starves the map in a fast turn
	 * (doc/frontend.md "Monocular mode"); 0 = insert whenever tracking asks (Default: 0.6) */
	double busyKeyFrameRatio{0.6};
	/** Threaded mode with [slam] mapping_lag > 0: replaces [slam] wait_for_weak_keyframes in
	 * monocular mode. After a keyframe inserted while local mapping was busy (tracking below
	 * busy_keyframe_ratio), tracking waits until local mapping is done with it: only keyframes
	 * make landmarks, and in a fast turn frames tracked ahead of them lose their last ones
	 * (doc/frontend.md "Modes") (Default: true) */
	bool waitForWeakKeyFrames{true};
	/** Reference-keyframe landmarks counted by that ratio: those seen by at least this many
	 * keyframes, 2 while the map has two keyframes (Default: 3, ORB-SLAM2's) */
	int keyFrameRefMinObservations{3};
	/** The two-view model (homography / fundamental matrix). */
	TwoViewOptions twoView;
	/** Bundle adjustment of the two first keyframes: the [mapping] options (set by the
	 * application, not INI keys of this section), with initBaIterations. */
	BundleAdjusterOptions ba;

	/** The [monocular] keys, the two-view model's included. */
	core::OptionFields fields();
	/** Throws std::invalid_argument naming section, key, value and rule of an invalid option. */
	void validate(const std::string& section = "monocular") const;
};

}  // namespace keygrid::sfm
