#pragma once
/** \file Tracker.h
 * Frame-to-map tracking: constant-velocity prediction, projection search against the local
 * map, Ceres pose refinement; PnP-RANSAC fallback and relocalization; keyframe decisions.
 * The tracker only creates keyframes and their new landmarks; refining the map around them
 * is the LocalMapper's job.
 *
 * Monocular mode (TrackerOptions::monocular; Tracker_monocular.cpp): the map starts from two
 * views (a reference frame, the following frames matched against it, TwoViewInitializer), at
 * the scale that puts the first keyframe's median scene depth at 1; keyframes bring no
 * landmarks of their own (the LocalMapper triangulates them) and are inserted by ORB-SLAM2's
 * monocular rule (MonocularOptions).
 */
#include <keygrid/core/Frame.h>
#include <keygrid/sfm/HocFrontend.h>
#include <keygrid/sfm/RollingShutter.h>
#include <keygrid/sfm/SparseMap.h>
#include <keygrid/sfm/TrackerOptions.h>
#include <keygrid/sfm/TwoViewInitializer.h>

#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace keygrid::sfm
{
enum class TrackingState
{
	NotInitialized,
	Ok,
	Lost
};

/** How the pose of a frame was found. */
enum class TrackingMethod
{
	Init,  //!< the frame started a map (first keyframe)
	Prediction,  //!< search around the motion model's prediction, then the local map
	Pnp,  //!< PnP-RANSAC on the reference keyframe's landmarks, then the local map
	Relocalization,  //!< after a loss: place recognition / newest keyframes, then the local map
	Lost  //!< not tracked
};
/** "init", "prediction", "pnp", "relocalization" or "lost" (frames.csv "method"). */
const char* toString(TrackingMethod m);

/** One inlier observation of a tracked frame, kept for the re-estimation of its pose against the
 * final map (the landmark's position is read from the map then). A run keeps one list per frame,
 * so it is stored compactly; the values are exactly those of the PoseObservation it stands for
 * (pixel and depth come from float features). */
struct FrameObservation
{
	double invSigma{1};  //!< 1 / scaleFactor^level
	float u{0}, v{0};  //!< undistorted pixel
	float depth{0};  //!< measured depth [m], 0 = none

	PoseObservation toPoseObservation(const Eigen::Vector3d& p_world) const
	{
		PoseObservation o;
		o.p_world = p_world;
		o.uv = {u, v};
		o.depth = depth;
		o.invSigma = invSigma;
		return o;
	}
};

/** What happened to one frame. */
struct TrackedFrame
{
	std::size_t index{0};
	double timestamp{0};
	mrpt::poses::CPose3D T_world_cam;
	bool tracked{false};
	TrackingMethod method{TrackingMethod::Lost};
	int matches{0}, inliers{0};
	bool newKeyFrame{false};
	KeyFrameId keyframe{0};  //!< the new keyframe when newKeyFrame
	/** Threaded mode: the new keyframe was inserted while local mapping was still busy, as
	 * tracking fell below the deferral share (Tracker::deferKeyFramesWhile). */
	bool keyFrameWhileMappingBusy{false};
	/** Pose relative to the reference keyframe, so the final trajectory follows map refinements. */
	KeyFrameId reference{0};
	mrpt::poses::CPose3D T_ref_cam;
	bool hasReference{false};
	/** Inlier observations of the frame: landmark ids and measurements, index for index. */
	std::vector<LandmarkId> observedLandmarks;
	std::vector<FrameObservation> observations;
	/** HOC bookkeeping of this frame (zero when [hoc] is disabled). */
	HocUpdateStats hoc;
	double hocSeconds{0};  //!< thread CPU time of HOC selection and update [s]
	bool hocFallback{false};  //!< tracked only with the HOC fallback selection (Tracker::track)
	/** When method is Relocalization and the frame was tracked: the keyframe it was found
	 * on, and whether place recognition (rather than the newest keyframes) proposed it. */
	KeyFrameId relocalizationKeyFrame{0};
	bool relocalizedByPlaceRecognition{false};
	/** Landmarks in the map after this frame (filled by the application). */
	std::size_t mapLandmarks{0};
	/** Monocular map start (method Init): the first keyframe of the new map, made of the
	 * reference frame `initialFrameIndex`; `keyframe` is the second one, this frame. */
	bool hasInitialKeyFrame{false};
	KeyFrameId initialKeyFrame{0};
	std::size_t initialFrameIndex{0};
	/** Monocular, before the map starts: what this frame did towards it (became the
	 * reference, or why the two-view initialization failed); empty otherwise. */
	std::string initMessage;
	/** Monocular, before the map starts: this frame became the reference frame. */
	bool initNewReference{false};
};

/** Place recognition for relocalization: keyframes that may show the same place as the
 * given features, best first, at most `maxCandidates` (the loop closer's vocabulary tree). */
using PlaceRecognizer = std::function<std::vector<KeyFrameId>(const FrameFeatures& features, int maxCandidates)>;

class Tracker
{
   public:
	Tracker(SparseMap& map, const TrackerOptions& opts);

	/** When set, relocalization tries these candidates before the newest keyframes. */
	void setPlaceRecognizer(PlaceRecognizer f) { m_placeRecognizer = std::move(f); }
	/** Threaded mode (ORB-SLAM2's rule): while `mappingBusy()` says local mapping is still
	 * working on a keyframe, a new one is inserted only at the keyframe timeout or when the
	 * frame tracks fewer than `weakRatio` x the reference keyframe's landmarks. Fewer
	 * keyframes, each of them mapped before the next; `weakRatio` in (0, 1]. A keyframe
	 * inserted while mapping is busy says so (TrackedFrame::keyFrameWhileMappingBusy). */
	void deferKeyFramesWhile(std::function<bool()> mappingBusy, double weakRatio);

	/** Tracks one frame whose features were extracted by the caller. In threaded mode the
	 * caller holds map.mutex() around this call (and around every other call). */
	TrackedFrame track(const core::Frame& frame, FrameFeatures features);

	TrackingState state() const { return m_state; }
	/** The map was loaded (a stored session): the next frame relocalizes in it (vocabulary
	 * tree, then the newest keyframes) instead of starting a new map. */
	void startInLoadedMap() { m_state = TrackingState::Lost; }
	/** Gives up relocalizing in the loaded map: the next frame starts a new map (a new
	 * KeyFrame::mapId, at the identity pose of a provisional frame) that loop closing merges
	 * into the loaded one when it finds a common place. */
	void startNewMap();
	/** false: localization only, no keyframe is created (the map stays as loaded apart from
	 * the landmarks' visibility counters and HOC histograms). (Default: true) */
	void setKeyFrameInsertion(bool on) { m_insertKeyFrames = on; }
	/** Median share of the local map in view matched by the recently tracked frames (the
	 * yardstick of a relocalization, see TrackerOptions::relocalizationShareFactor); nullopt
	 * before the first tracked frame. */
	std::optional<double> recentShareMedian() const;
	/** A loaded map: the yardstick as the mapping run left it, for the first relocalization
	 * (later frames replace it). */
	void seedRecentShare(double share) { m_recentShares.assign(1, share); }
	/** After a map correction (loop closure) moved the last tracked frame: its new pose. The
	 * motion model (relative) stays valid. */
	void onMapCorrected(const mrpt::poses::CPose3D& T_world_lastFrame) { m_lastPose = T_world_lastFrame; }
	/** After a map correction, when the last frame's new pose is not known (threaded mode:
	 * tracking went on while the loop was closed): the last frame follows its reference
	 * keyframe. */
	void onMapCorrected();
	/** After the map was scaled by s about the world origin (SparseMap::rescale: a monocular
	 * map given metric scale): the last pose, the motion model and the last frame's pose
	 * relative to its reference keyframe scale with it. */
	void onMapRescaled(double s);
	/** After the newest stretch of the map was rescaled, the reference keyframe's content by s
	 * about it (slam::MetricScale's window rescale): the motion model and the last frame's pose
	 * relative to its reference scale by s, and the last frame follows its reference. */
	void onMapRescaledLocally(double s);
	const TrackerOptions& options() const { return m_opts; }
	/** Landmarks matched as inliers in the last frame (for diagnostics and the maps). */
	const std::vector<LandmarkId>& lastInlierLandmarks() const { return m_lastInliers; }

   private:
	/** The motion model and the last frame's pose relative to its reference, scaled by s. */
	void scaleMotion(double s);

	struct Current
	{
		const core::Frame* frame{nullptr};
		FrameFeatures features;
		std::vector<LandmarkId> matches;
		mrpt::poses::CPose3D T_world_cam;
		int inliers{0};
		/** Local-map landmarks in view of the pose searched by trackLocalMap (matched or not) */
		int localMapInView{0};
		/** HOC: local-map landmarks projected for the final search, those the selection
		 * excluded, and those matched before it (see HocFrontend::update). */
		std::vector<ProjectedLandmark> hocVisible, hocExcluded;
		std::vector<LandmarkId> matchedBeforeLocalMap;
	};

	bool initialize(Current& cur, TrackedFrame& out);
	/** Monocular map start: a reference frame, then two-view initialization with each next
	 * frame (retried, the reference replaced when it matches too few or after
	 * init_max_frames); true when this frame started the map. */
	bool initializeMonocular(Current& cur, TrackedFrame& out);
	/** After a map start: tracking goes on from cur (its pose T_world_cam set) with the local
	 * keyframes `localKfs`, the newest first (it becomes the reference keyframe), and no motion
	 * model yet; out reports the start with `landmarks` as its matches and inliers. */
	void startTrackingOnNewMap(const Current& cur, TrackedFrame& out, std::vector<KeyFrameId> localKfs, int landmarks);
	/** The map of a successful two-view initialization: two keyframes, the triangulated
	 * landmarks, their bundle adjustment, median depth 1; false (map untouched, reason in
	 * out.initMessage) when too few landmarks survive. `pairs` holds the (reference, current)
	 * keypoints of each correspondence of `r`, in its order. */
	bool startMonocularMap(Current& cur, const TwoViewResult& r, const std::vector<std::pair<int, int>>& pairs, TrackedFrame& out);
	/** The current frame becomes the monocular reference frame. */
	void setMonocularReference(const Current& cur);
	/** One tracking attempt of an initialized tracker: motion model / PnP or relocalization,
	 * then the local map; fills out.method; true when the pose is good. */
	bool attempt(Current& cur, TrackedFrame& out);
	bool trackByPrediction(Current& cur);
	/** Descriptor matches with keyframe kf's landmarks, PnP-RANSAC, refinement; succeeds with
	 * at least minRefinedInliers inliers after the refinement. */
	bool trackByPnp(Current& cur, KeyFrameId kf, int minRefinedInliers);
	bool relocalize(Current& cur);
	/** Projects the local map's unmatched landmarks, matches, refines; returns inliers. */
	int trackLocalMap(Current& cur, float radius);
	/** Refines cur.T_world_cam from cur.matches; drops outlier matches; returns inliers.
	 * `anchored`: the final refinement against the local map, anchored on the landmarks seen by
	 * >= anchor_min_keyframes keyframes (optimizePoseAnchored). */
	int refinePose(Current& cur, bool anchored = false);
	void updateLocalKeyFrames(const Current& cur);
	/** Local-map landmarks in view of cur's pose, not yet matched and (with HOC) selected for
	 * this camera; with `forLocalMap` they are counted as visible and the HOC lists of cur are
	 * filled. */
	std::vector<ProjectedLandmark> projectLocalLandmarks(Current& cur, bool forLocalMap);
	/** HOC selection of one landmark for cur's camera (always true without HOC). */
	bool hocUsable(LandmarkId id, const Current& cur);
	bool hocUsable(Landmark& lm, const Current& cur);
	/** Rolling shutter, after a successful attempt: the keypoints compensated again with the
	 * rates of the step from the last frame to cur's pose, and the pose refined on them. */
	void recompensateRollingShutter(Current& cur, const RollingShutterCompensator& rs);
	/** Time since the last tracked frame when it is short enough to average rates over [s],
	 * else 0. */
	double stepDuration(double timestamp) const;
	/** HOC update and pruning after the pose of cur is final. */
	void updateHoc(Current& cur, TrackedFrame& out);
	/** Whether this frame becomes a keyframe (needKeyFrame*, insertUnlessDeferred). */
	enum class KeyFrameNeed
	{
		No,
		Yes,
		YesWhileMappingBusy  //!< see TrackedFrame::keyFrameWhileMappingBusy
	};
	KeyFrameNeed needKeyFrame(const Current& cur) const;
	/** ORB-SLAM2's monocular rule: fewer tracked landmarks than keyframe_tracked_ratio x the
	 * reference keyframe's (seen by >= keyframe_ref_min_observations keyframes), or the
	 * keyframe timeout; and enough inliers. */
	KeyFrameNeed needKeyFrameMonocular(const Current& cur) const;
	KeyFrameId createKeyFrame(const Current& cur);
	/** A keyframe of the current frame: its time, pose, features, depth and colour image. */
	static KeyFrame keyFrameOf(const Current& cur);

	SparseMap& m_map;
	TrackerOptions m_opts;
	TrackingState m_state{TrackingState::NotInitialized};
	PinholeIntrinsics m_K;
	mrpt::poses::CPose3D m_lastPose;
	std::optional<mrpt::poses::CPose3D> m_velocity;  //!< T_last_cur of the last tracked step
	double m_velocityDt{0};  //!< time that step took [s] (0: unknown)
	double m_lastTimestamp{0};  //!< timestamp of the last tracked frame [s]
	KeyFrameId m_refKf{0};
	/** HOC: the current attempt uses the fallback selection (see track()) */
	bool m_hocRelaxed{false};
	/** Share of the local map in view matched by the last kRecentShares tracked frames (not
	 * relocalizations): the yardstick of requiredRelocalizationShare(). */
	static constexpr std::size_t kRecentShares = 30;
	std::deque<double> m_recentShares;
	/** The last frame's reference keyframe and its pose relative to it. */
	std::optional<std::pair<KeyFrameId, mrpt::poses::CPose3D>> m_lastRelative;
	std::size_t m_lastKfFrame{0};
	std::vector<KeyFrameId> m_localKfs;
	std::vector<LandmarkId> m_lastInliers;
	int m_framesLost{0};
	std::optional<HocFrontend> m_hoc;
	PlaceRecognizer m_placeRecognizer;
	std::function<bool()> m_mappingBusy;  //!< see deferKeyFramesWhile (empty: never deferred)
	double m_deferWeakRatio{0};  //!< set with m_mappingBusy
	/** needKeyFrame's last step: `wanted` (a keyframe by the mode's own rule) unless local
	 * mapping is busy and tracking not weak enough to insist (deferKeyFramesWhile). */
	KeyFrameNeed insertUnlessDeferred(bool wanted, bool timeout, int inliers, int refMatches) const;
	bool m_insertKeyFrames{true};  //!< see setKeyFrameInsertion
	std::uint32_t m_newMapId{0};  //!< KeyFrame::mapId of the map initialize() starts
	bool m_relocRecognized{false};  //!< the last relocalize() succeeded on a recognized place
	double m_hocSelectionSeconds{0};  //!< CPU time of the HOC selection in the current frame
	/** Monocular map start: the reference frame, and where each of its keypoints was last
	 * matched (the centre of its next search window). */
	struct MonocularReference
	{
		std::size_t index{0};
		double timestamp{0};
		cv::Mat colour;
		FrameFeatures features;
		std::vector<cv::Point2f> predicted;
		/** Plane normals of the motions of the first ambiguous two-view result with this
		 * reference (see MonocularOptions::initPlaneNormalDeg) */
		std::vector<Eigen::Vector3d> ambiguousNormals;
	};
	/** An ambiguous homography result with this reference resolved by the plane the first
	 * ambiguous result implied: the index of the candidate to take, or nullopt. */
	std::optional<std::size_t> resolvePlaneAmbiguity(const TwoViewResult& r);
	std::optional<MonocularReference> m_monoRef;
};

}  // namespace keygrid::sfm
