#pragma once
/** \file CameraHeightScale.h
 * Metric scale of a monocular map from the camera's known height above the floor:
 * the floor plane is estimated among the map points below the keyframe cameras, each
 * keyframe's height above it is measured in map units, and
 *
 *     s = camera_height / h_map,   h_map = median over keyframes of n . c_k + d,
 *
 * converts map units to metres (multiply translations and points by s). The caller applies s
 * to its map (a Sim(3) or SE(3) representation) and re-estimates as the map grows: the
 * estimator is stateless.
 *
 * Which plane is the floor: the LOWEST large plane roughly perpendicular to "up" that has the
 * cameras above it, found by maps::estimateLowestFloorPlane (the RGB-D floor frame's search,
 * reused unchanged): hypotheses come from the lowest points, a plane with many points under it
 * is not the floor (a desk or sofa top holds more points than the floor seen beyond it, but the
 * floor's points lie below it), and the winner is refined by least squares on its inliers,
 * its tilt also from the large planes parallel to it (furniture tops) and perpendicular to it
 * (walls). "Up" is the mean of the keyframe cameras' -y axes (optical frame, y down): a camera
 * at a fixed height on a robot is roughly level, and the search allows maxTiltDeg off it.
 *
 * Once the keyframes have turned (yaw) by levelMinTurnDeg or more, their orientations say
 * where the floor is: a camera mounted on a robot without roll keeps its x axis parallel to
 * the floor, so the x axes x_k of keyframes facing different ways span the floor's directions
 * and the floor's normal is the direction least along them, the eigenvector of the smallest
 * eigenvalue of sum_k x_k x_k^T (the "turn axis"). The map's scale does not touch it, and on a
 * short, narrow path, where the cameras' positions cannot tell the floor from a plane rolled
 * about the path, it can. A floor that would be taken but lies more than levelMaxTiltDeg off
 * the turn axis is then refused, and the search is run again with the turn axis as its hint
 * and levelMaxTiltDeg as its tolerance (a search that failed is not run again); its floor is
 * refused too when its refinement (walls, furniture tops) tilted it that far off the axis.
 * A mount roll r tilts the turn axis by about r; the tolerance covers a few degrees of it.
 *
 * Which points count: a point is "below the cameras" when, seen from its nearest keyframe
 * camera, it lies at least minDepressionDeg under the horizontal (the plane through the camera
 * perpendicular to "up"). The test is an angle, so it needs no scale; it drops the ceiling and
 * the upper walls, which cannot be the floor but would dilute the support shares.
 *
 * The map's scale is arbitrary, while the plane search has metric tolerances (inlier band,
 * wall and furniture extents): the search runs on the map rescaled to approximately metres by
 * the current estimate, and is repeated (at most 4 times) until its result is within 1 % of
 * the scale it ran at. The first estimate takes h_map as the 95th percentile of the points'
 * depth below their nearest camera along "up": the floor is the lowest surface, so the upper
 * tail of that depth is the camera height. A later search that finds no floor refuses: a
 * plane found at a wrong first scale (a band through walls or clutter) is not confirmed at
 * its own.
 *
 * Limits: the floor must be the lowest large plane the map holds (a lower level seen through
 * a stairwell or a glass floor would be taken instead); points of walls and furniture within
 * the inlier band above the floor are counted as floor and lift it by a fraction of the band;
 * the floor points' height noise must stay well inside the band (map points refined by bundle
 * adjustment, not fresh two-view triangulations), or the search may settle on a plane tilted
 * through the floor and the feet of the walls.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/poses/CPose3D.h>

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace keygrid::sfm
{
/** Lengths marked [m] are metres of the map rescaled by the current scale estimate. */
struct CameraHeightScaleOptions : public core::FieldTableOptions<CameraHeightScaleOptions>
{
	/** Height of the camera's optical centre above the floor [m]; 0 = not known: the map
	 * stays up to scale and the estimator cannot be built (Default: 0) */
	double cameraHeight{0.0};
	/** Fewer keyframes are refused: the spread of their heights needs a few (Default: 3) */
	int minKeyframes{3};
	/** Fewer map points below the cameras are refused (Default: 200) */
	int minPointsBelow{200};
	/** A point counts as below the cameras when its nearest keyframe camera sees it at least
	 * this far under the horizontal [deg] (Default: 5 deg: the floor up to 11 camera heights
	 * away) */
	double minDepressionDeg{5.0};
	/** Point-to-plane distance of a floor inlier [m]. A map point errs mostly along its ray,
	 * with a depth std d^2 sigma_px / (f B) over a baseline B, so a floor point seen from height
	 * h at distance d has a height std of h / d of that; the band holds a few of those for
	 * points refined by local bundle adjustment, so it is wider than the RGB-D floor's
	 * (doc/frontend.md, "Metric scale from the camera height") (Default: 0.05 m) */
	double inlierDistance{0.05};
	/** A point this far under a plane is below it; a plane with many points below is not the
	 * floor. Far enough that the floor's own noise does not count against it [m]
	 * (Default: 0.10 m) */
	double belowDistance{0.10};
	/** A plane with more points below it than this share of the least floor support
	 * (minFloorShare, minFloorPoints) is not the floor (maps::FloorFrameOptions::
	 * maxBelowShare). A monocular map keeps a few points triangulated far along their rays,
	 * under the floor: over a long stretch of path they can outnumber half the least support
	 * (slam::MetricScale searches its window with a generous share) (Default: 0.5) */
	double maxBelowShare{0.5};
	/** Largest angle between the floor's normal and the cameras' mean -y axis [deg]: covers a
	 * camera pitched down towards the floor (Default: 40 deg) */
	double maxTiltDeg{40.0};
	/** Once the keyframes' x axes have turned this much about one axis, a floor further than
	 * levelMaxTiltDeg off that axis is refused and searched for around it [deg]; 0 = never
	 * (Default: 15 deg) */
	double levelMinTurnDeg{15.0};
	/** Largest angle between the floor's normal and the keyframes' turn axis [deg]: the mount's
	 * roll and the rotations' noise (Default: 4 deg) */
	double levelMaxTiltDeg{4.0};
	/** RANSAC plane hypotheses per search round (Default: 3000) */
	int hypotheses{3000};
	/** Least floor support: this share of the points below the cameras ... (Default: 0.02) */
	double minFloorShare{0.02};
	/** ... and at least this many points (Default: 50) */
	int minFloorPoints{50};
	/** Refused when the robust spread of the keyframes' heights (1.4826 MAD / median) exceeds
	 * this share: the cameras are not at one height, or the map's scale drifts (Default: 0.05) */
	double maxHeightSpread{0.05};
	/** RANSAC seed: the same seed and input give the same estimate (Default: 1) */
	uint32_t seed{1};

	/** The INI keys, with description and rule (core/OptionFields.h). */
	core::OptionFields fields();
	/** Throws std::invalid_argument("[section] key = value (must be ...)") on a bad value. */
	void validate(const std::string& section = "camera_height_scale") const;
};

enum class CameraHeightScaleFailure
{
	None,
	TooFewKeyframes,  //!< fewer keyframes than minKeyframes
	TooFewPointsBelow,  //!< fewer map points below the cameras than minPointsBelow
	NoFloorPlane,  //!< no large plane near perpendicular to "up" with the cameras above it
	FloorNotClear,  //!< every large plane has many points under it: the floor was not seen
	HeightSpread,  //!< the keyframes' heights above the floor spread more than maxHeightSpread
	NotConverged,  //!< the scale kept changing between searches
	OffTurnAxis  //!< the floor found around the turn axis ended levelMaxTiltDeg or more off it
};

const char* toString(CameraHeightScaleFailure f);

struct CameraHeightScaleResult
{
	bool ok{false};
	CameraHeightScaleFailure failure{CameraHeightScaleFailure::None};
	std::string message;  //!< why it failed (or what it found), with the numbers
	/** s = cameraHeight / heightMap: metres per map unit; 0 when no floor was accepted (also set when refused for
	 * HeightSpread, NotConverged or OffTurnAxis) */
	double scale{0};
	/** Median of keyframeHeights [map units] */
	double heightMap{0};
	/** 1.4826 MAD of keyframeHeights / heightMap (robust relative std) */
	double heightSpread{0};
	/** Per keyframe (input order): its camera centre's signed height above the floor [map
	 * units]; empty when no plane was found */
	std::vector<double> keyframeHeights;
	/** The floor n . p + d = 0 in the map's frame, n unit and pointing towards the cameras,
	 * d in map units */
	Eigen::Vector3d floorNormal{Eigen::Vector3d::Zero()};
	double floorOffset{0};
	std::size_t pointsBelow{0};  //!< map points below the cameras (the search's input)
	std::size_t floorInliers{0};  //!< of them, within inlierDistance of the floor
	std::size_t pointsUnderFloor{0};  //!< of them, more than belowDistance under the floor
	/** Horizontal (the floor included) and vertical planes the floor's tilt was fitted to */
	std::size_t parallelPlanes{0}, verticalPlanes{0};
	int passes{0};  //!< plane searches run (each on the map rescaled by the previous scale)
	/** The turn axis in the map's frame (unit, towards the cameras' mean -y) and how far the
	 * keyframes' x axes turned about it [deg]: the arc their headings cover, 360 deg less the
	 * largest gap between neighbouring headings; zero with fewer than two keyframes */
	Eigen::Vector3d turnAxis{Eigen::Vector3d::Zero()};
	double turnDeg{0};
	/** The floor was searched for around the turn axis: the keyframes turned levelMinTurnDeg
	 * or more and the first search's floor lay off it */
	bool searchedAroundTurnAxis{false};
	/** Angle between the floor found and the turn axis [deg]; NaN when no plane was found */
	double floorToTurnAxisDeg{std::numeric_limits<double>::quiet_NaN()};
};

class CameraHeightScaleEstimator
{
   public:
	/** Throws std::invalid_argument when the options are invalid or cameraHeight is 0. */
	explicit CameraHeightScaleEstimator(const CameraHeightScaleOptions& opts);

	/** The scale of a map given its keyframe poses (T_world_cam, optical frame) and landmark
	 * positions, both in the map's frame and units. Thread-safe (const, no state); throws
	 * std::invalid_argument on a non-finite point or pose. */
	CameraHeightScaleResult estimate(
		const std::vector<mrpt::poses::CPose3D>& T_world_cam, const std::vector<Eigen::Vector3d>& points_world) const;

	const CameraHeightScaleOptions& options() const { return m_opts; }

   private:
	CameraHeightScaleOptions m_opts;
};

/** The map scaled by s about the world origin (x -> s x): camera centres and points times s,
 * orientations unchanged. */
void rescaleMap(double s, std::vector<mrpt::poses::CPose3D>& T_world_cam, std::vector<Eigen::Vector3d>& points_world);

}  // namespace keygrid::sfm
