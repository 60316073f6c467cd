#pragma once
/** \file FloorFrameEstimator.h
 * One floor frame for a whole run: T_world_floor (z up, z = 0 on the floor) in a SLAM world
 * that is not gravity aligned (the first camera's optical frame), shared by every map output.
 *
 * The floor is "the lowest large horizontal plane consistent with the cameras' height":
 * estimateLowestFloorPlane() finds it among depth samples pooled over keyframes, and
 * FloorFrameEstimator keeps those samples in a bounded reservoir, in their keyframes' camera
 * frames, so that the estimate follows corrected keyframe poses and is refined as the map
 * grows. No frame source of keygrid carries an IMU or accelerometer: "up" comes from the
 * cameras (the mean of their -y axes) or from the INI (up_hint), and the whole frame can be
 * given instead of estimated (T_world_floor).
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>
#include <keygrid/maps/FloorPlaneEstimator.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/math/TPoint3D.h>
#include <mrpt/poses/CPose3D.h>

#include <cstdint>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace keygrid::maps
{
/** Options of the floor frame of a run (INI section [floor] of keygrid-slam). */
struct FloorFrameOptions : public core::FieldTableOptions<FloorFrameOptions>
{
	/** The floor frame given instead of estimated, "[x y z yaw pitch roll]" (m, deg) in the
	 * SLAM world; empty (INI: "estimate") = estimate it (Default: empty) */
	std::string givenPose;
	/** "Up" in the SLAM world for the first search, "x y z"; (0 0 0) = the mean -y axis of
	 * the keyframe cameras so far (Default: 0 0 0) */
	mrpt::math::TVector3D upHint{0, 0, 0};
	/** The floor is estimated at every keyframe until this many keyframes contributed samples
	 * (and until it is found) (Default: 10) */
	int initialKeyframes{10};
	/** After that, re-estimated every this many keyframes and after each trajectory
	 * correction (Default: 10) */
	int reestimateEvery{10};
	/** Samples kept, a uniform random subset of all keyframes' samples (reservoir sampling)
	 * (Default: 60000) */
	int reservoirSize{60000};
	/** Depth samples of a keyframe: every n-th pixel in rows and columns (Default: 12) */
	int pixelStep{12};
	/** Depth range of the samples [m] (Default: 0.3 .. 4.0 m) */
	double minDepth{0.3}, maxDepth{4.0};
	/** A new estimate replaces the old one (and the 2D grids re-integrate) only when the floor
	 * moved by more than this at the first keyframe's footprint [m] (Default: 0.002 m) ... */
	double minChange{0.002};
	/** ... or tilted by more than this [deg] (Default: 0.05 deg) */
	double minChangeDeg{0.05};

	/** Point-to-plane distance of a floor inlier [m] (Default: 0.02 m) */
	double inlierDistance{0.02};
	/** RANSAC hypotheses per round (Default: 3000) */
	int hypotheses{3000};
	/** Rounds of search; after the first, "up" is the previous round's plane normal
	 * (Default: 3) */
	int rounds{3};
	/** Largest angle between a plane's normal and "up" in the first round [deg]: the mean
	 * -y of a few hand-held cameras that look down at the floor is off by their pitch
	 * (Default: 40 deg) */
	double maxTiltDeg{40.0};
	/** The same in the later rounds, around the previous normal [deg] (Default: 5 deg) */
	double refineTiltDeg{5.0};
	/** Hypotheses are sampled among this share of the samples that are lowest along "up"
	 * (Default: 0.10) */
	double lowestFraction{0.10};
	/** Least support of a floor: this share of all samples... (Default: 0.005) */
	double minSupport{0.005};
	/** ... and at least this many samples (Default: 100) */
	int minSupportPoints{100};
	/** A sample lower than a plane by more than this is "below" it [m] (Default: 0.05 m) */
	double belowDistance{0.05};
	/** A plane with more samples below it than this share of the least support is not the
	 * floor (a table top has the floor under it) (Default: 0.5) */
	double maxBelowShare{0.5};
	/** The floor's tilt from every large horizontal plane (floor, furniture tops, ceiling:
	 * parallel planes with a common normal), its height from the floor alone; false = from
	 * the floor alone (Default: true) */
	bool parallelPlanes{true};
	/** With parallelPlanes: the normal is also fitted perpendicular to the large vertical
	 * planes (walls, cabinet fronts). A floor seen as a strip at the foot of a wall leaves its
	 * tilt towards the wall to the depth noise, the wall pins exactly that (Default: true) */
	bool verticalPlanes{true};
	/** Every keyframe camera but 5 % must be at least this high above the floor [m]
	 * (Default: 0.2 m) */
	double minCameraHeight{0.2};
	/** estimateLowestFloorPlane only, not an INI key: when the plane found has at least the
	 * least support's worth of samples below it, search those samples alone, and a large plane
	 * among them (the floor under a desk top) is the floor instead; stray samples scattered
	 * under the floor form none. Set by the monocular camera-height estimator, whose maps keep
	 * such stray points (Default: false) */
	bool searchUnderTheWinner{false};
	/** Random seed of the reservoir and of RANSAC (Default: 1) */
	uint32_t seed{1};

	/** The [floor] keys (`T_world_floor` = estimate | [x y z yaw pitch roll], `up_hint`,
	 * `initial_keyframes`, ...). */
	core::OptionFields fields();
	/** Throws std::invalid_argument naming section, key, value and rule of an invalid option. */
	void validate(const std::string& section = "floor") const;
	/** givenPose parsed; nullopt when empty. */
	std::optional<mrpt::poses::CPose3D> given() const;
};

/** What estimateLowestFloorPlane() found. */
struct FloorPlaneFit
{
	FloorPlane plane;
	/** Samples more than belowDistance under the plane. */
	std::size_t below{0};
	/** False when no large horizontal plane had (almost) nothing below it, and the plane with
	 * the fewest samples below it was taken (the floor was not seen: e.g. a desk). */
	bool clearBelow{true};
	/** Horizontal planes the normal was fitted to (1: the floor alone), and vertical ones. */
	std::size_t parallelPlanes{1}, verticalPlanes{0};
};

/** The lowest large horizontal plane among `points_world` with the cameras above it.
 *
 * Each round samples plane hypotheses from triples of the `lowestFraction` lowest points along
 * `up`, keeps those within the tilt bound whose normal keeps every camera but 5 % at least
 * minCameraHeight above them, and scores them on an even subsample: support (points within
 * inlierDistance) and points below (more than belowDistance under the plane). A plane with
 * fewer than the least support is not considered; among the rest, the one with the most
 * support and few points below wins: a table or sofa top can hold far more points than the
 * floor, but the floor's points lie under it. The winner is refined by least squares on its
 * inliers (weighted by `weights` when given, one per point; iterated until it settles) and
 * its normal becomes "up" of the next round. When every large plane has points below it, the
 * one with the fewest below is returned with clearBelow = false. Last, with parallelPlanes,
 * the normal is refitted to all large planes parallel to the floor (furniture tops) and, with
 * verticalPlanes, perpendicular to the large vertical ones (walls); the height to the floor's
 * points. */
std::optional<FloorPlaneFit> estimateLowestFloorPlane(
	const std::vector<mrpt::math::TPoint3D>& points_world, const mrpt::math::TVector3D& up_world,
	const std::vector<mrpt::math::TPoint3D>& cameras_world, const FloorFrameOptions& opts,
	const std::vector<double>& weights = {});

/** The floor frame of a run, pooled over its keyframes (see the file comment). */
class FloorFrameEstimator
{
   public:
	/** One accepted estimate. */
	struct Update
	{
		std::size_t keyframes{0};  //!< keyframes that had contributed samples
		double stamp{0};  //!< timestamp of the newest of them [s]
		mrpt::poses::CPose3D T_world_floor;
		std::size_t samples{0}, inliers{0}, below{0};
		bool clearBelow{true};
		std::size_t planes{1}, walls{0};  //!< horizontal and vertical planes of the tilt fit
	};

	explicit FloorFrameEstimator(const FloorFrameOptions& opts = {});

	const FloorFrameOptions& options() const { return m_opts; }
	/** Adds a keyframe's samples (its camera frame) at its pose, taken at `stamp` [s];
	 * re-estimates when the schedule says so. Returns true when the floor frame changed. A
	 * keyframe added again only updates its pose. */
	bool addKeyframe(
		uint64_t id, const mrpt::poses::CPose3D& T_world_cam,
		const std::vector<mrpt::math::TPoint3Df>& samples_cam, double stamp = 0);
	/** New poses of known keyframes (others are ignored), then a re-estimate. `scales` (id ->
	 * factor, absent: 1; a monocular Sim(3) correction) scales a keyframe's samples in its
	 * camera frame. Returns true when the floor frame changed. */
	bool updatePoses(
		const std::map<uint64_t, mrpt::poses::CPose3D>& newPoses, const std::map<uint64_t, double>& scales = {});
	/** Re-estimates from the reservoir now; true when the floor frame changed. */
	bool reestimate();

	/** The floor frame: given, or the last accepted estimate; nullopt before the first. */
	const std::optional<mrpt::poses::CPose3D>& T_world_floor() const { return m_T_world_floor; }
	bool given() const { return m_given; }
	/** Accepted estimates in order (empty when given). */
	const std::vector<Update>& history() const { return m_history; }
	std::size_t keyframes() const { return m_poses.size(); }
	std::size_t samples() const { return m_samples.size(); }
	/** Estimates run and their total wall time [s]. */
	std::size_t estimates() const { return m_estimates; }
	double seconds() const { return m_seconds; }
	/** JSON object: source ("given" | "estimated" | "none"), T_world_floor [x y z qx qy qz qw],
	 * keyframes, samples, estimates, seconds and the history. */
	std::string toJson() const;

	/** Depth samples in the camera frame of a depth image (metres, float, row-major) of a
	 * pinhole camera: every pixelStep-th pixel (starting at pixelStep / 2), within the depth
	 * range, lens distortion ignored. */
	static std::vector<mrpt::math::TPoint3Df> depthSamples(
		const float* depth, int rows, int cols, double fx, double fy, double cx, double cy,
		const FloorFrameOptions& opts);

   private:
	struct Sample
	{
		uint64_t keyframe;
		mrpt::math::TPoint3Df p_cam;
	};
	FloorFrameOptions m_opts;
	bool m_given{false};
	std::optional<mrpt::poses::CPose3D> m_T_world_floor;
	std::optional<FloorPlane> m_plane;  //!< plane of the last accepted estimate
	std::map<uint64_t, mrpt::poses::CPose3D> m_poses;  //!< keyframes with samples, current poses
	uint64_t m_firstKeyframe{0};
	double m_lastStamp{0};  //!< timestamp of the newest keyframe
	std::vector<Sample> m_samples;
	std::size_t m_seen{0};  //!< samples offered to the reservoir
	std::mt19937 m_rng;
	std::vector<Update> m_history;
	std::size_t m_estimates{0};
	double m_seconds{0};

	bool due() const;
};

}  // namespace keygrid::maps
