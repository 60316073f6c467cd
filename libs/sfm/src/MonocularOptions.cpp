#include <keygrid/sfm/MonocularOptions.h>
#include <mrpt/config/CConfigFileBase.h>

namespace keygrid::sfm
{
core::OptionFields MonocularOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("init_min_keypoints", initMinKeypoints, "keypoints a frame needs to become the reference of the map start", R::positive());
	f.add("init_max_frames", initMaxFrames, "frames after which a reference that did not initialize is replaced", R::positive());
	f.add("init_window_px", initWindowPx, "search window of the matching against the reference [px at level 0]", R::positive());
	f.add("init_max_distance_orb", initMaxDistanceOrb, "largest ORB descriptor distance of an initial match [Hamming bits]", R::positive());
	f.add("init_max_distance_sift", initMaxDistanceSift, "largest SIFT descriptor distance of an initial match [L2]", R::positive());
	f.add("init_ratio", initRatio, "best / second-best distance ratio of an initial match", R::aboveUpTo(0, 1));
	f.add("init_check_orientation", initCheckOrientation, "keep initial matches with a consistent orientation change");
	f.add("init_plane_normal_deg", initPlaneNormalDeg, "ambiguous plane motions: take the one whose plane stays within this angle [deg]; 0 = off", R::inRange(0, 90));
	f.add("init_min_landmarks", initMinLandmarks, "landmarks the two-view map must keep after its bundle adjustment", R::positive());
	f.add("init_ba_iterations", initBaIterations, "bundle adjustment iterations of the two first keyframes", R::positive());
	f.add("keyframe_tracked_ratio", keyFrameTrackedRatio, "new keyframe below this share of the reference's landmarks", R::aboveUpTo(0, 1));
	f.add("busy_keyframe_ratio", busyKeyFrameRatio, "threaded, lag > 0, monocular: replaces [slam] busy_keyframe_ratio (0: off)", R::inRange(0, 1));
	f.add("wait_for_weak_keyframes", waitForWeakKeyFrames, "threaded, lag > 0, monocular: replaces [slam] wait_for_weak_keyframes");
	f.add("keyframe_ref_min_observations", keyFrameRefMinObservations, "reference landmarks counted: seen by >= this many keyframes", R::positive());
	f.append(twoView.fields());
	return f;
}

void MonocularOptions::validate(const std::string& s) const
{
	core::validateFields(*this, s);
	twoView.validate(s);
}

}  // namespace keygrid::sfm
