#pragma once
/** \file GridMorphing.h
 * Grid morphing (the paper's Fig. 1b): re-anchors occupancy grids built along an old camera
 * trajectory onto a corrected trajectory, without re-integrating raw depth.
 *
 * For every voxel X^ of the corrected grid and every corrected keyframe camera P^_i whose view
 * cone contains X^, the voxel's earlier position is X_i = T_old_i * inv(T_new_i) * X^ (the point
 * keeps its coordinates in camera i). The log-odds L_i of X_i is read (nearest voxel) from the
 * submap keyframe i was integrated into, and the corrected value is the weighted average
 *
 *     L(X^) = sum_i w_i L_i / sum_i w_i,   w_i = 1 / max(z_i, zMin)^p,
 *
 * over the cameras whose submap knows X_i (L_i read with trilinear interpolation by default,
 * see MorphingOptions::interpolation), with z_i = |X^ - C^_i| the distance from X^ to the
 * corrected camera centre. Choice of w: Kinect-type depth noise grows with z^2 (Khoshelham &
 * Elberink 2012), so near views carry sharper evidence; p = 2 (default) weights by inverse
 * standard deviation, p = 4 would be inverse variance. zMin keeps very near voxels from dominating.
 * Averaging (not summing) keeps the confidence of a voxel seen by many keyframes unchanged, so an
 * identity correction returns the grid unchanged.
 *
 * Travelled distance: inside one submap the grid mixes frames integrated with different drift,
 * and the correction of keyframe i is only right for the content i (or a keyframe close to i
 * along the trajectory) placed. Each voxel remembers the travelled distance of its last updater,
 * so a lookup through keyframe i counts only when |s_voxel - s_i| <= travelWindow; a voxel none
 * of whose lookups passes keeps the value of its source voxel, moved with its last updater's
 * correction (step 3 below). With consistent submaps this changes little; it matters when drift
 * accumulated inside a submap.
 *
 * Which X^ are evaluated: each known source voxel is mapped forward through the keyframe of its
 * submap whose travelled distance is closest to the voxel's (the camera that most likely last
 * updated it); every corrected voxel in the blocks touched by these forward images is evaluated.
 * Source voxels whose forward image received no value (outside every corrected cone, or no
 * lookup in the travel window) keep their value and move rigidly with that same keyframe (an
 * extension: the paper only describes voxels inside the cones).
 *
 * Cost (none of these changes a value the definition above gives; the unit test compares every
 * voxel with a brute-force evaluation): keyframes are culled per corrected 8^3 block, by the
 * block's box against the view pyramid (box centre and half extents against the 5 faces, 1e-9 m
 * margins: inside everywhere -> no per-voxel cone test) and by whether the source blocks their
 * lookups can reach hold a known voxel in their travel window (per source block: sorted
 * distinct travelled distances with counts, bounding boxes and 512-bit voxel masks). Per
 * (block, keyframe) the camera-frame and earlier positions are affine in the voxel index; the
 * tests that select voxels (within one voxel of the box of readable source voxels, in front of
 * the camera, inside the 4 side planes) are clipped per block along z, per slice along y and
 * per row along x, and where the cone tests hold by more than 1e-9 m the per-voxel cone test is
 * skipped. Per lookup, the cube of the 8 trilinear corners is first tested against the source
 * block's mask of voxels known in the window, dilated by one voxel (two blocks' masks when the
 * cube crosses one block face): no bit, no lookup. Optionally (maxKeyframesPerBlock) only the K
 * keyframes with the most readable voxels times weight are kept per block: an approximation.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/maps/VoxelBlockGrid.h>
#include <mrpt/poses/CPose3D.h>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace keygrid
{
/** Old and corrected pose of one keyframe's optical camera frame. */
struct PoseCorrection
{
	mrpt::poses::CPose3D T_world_cam_old;
	mrpt::poses::CPose3D T_world_cam_new;
	/** What the keyframe holds in its camera frame (map points, rays) grows by this factor:
	 * new map units per old in that frame. A Sim(3) correction of a monocular map (loop
	 * closing) gives each keyframe its own similarity, scale included, and the landmarks it
	 * placed follow it; 1 for a rigid correction. */
	double scale{1.0};
};
/** keyframe id -> {old pose, new pose}. */
using TrajectoryCorrection = std::map<uint64_t, PoseCorrection>;

struct MorphingOptions : public core::FieldTableOptions<MorphingOptions>
{
	/** Depth of the keyframe view cones [m] (Default: 4 m, the integration max range) */
	double viewConeMaxRange{4.0};
	/** Exponent p of the weight 1 / z^p (Default: 2) */
	double weightExponent{2.0};
	/** Distances below this count as this in the weights [m] (Default: 0.5 m) */
	double minWeightDistance{0.5};
	/** Travelled-distance window [m]: a lookup through keyframe i only counts when the looked-up
	 * voxel was last updated within this travelled distance of keyframe i (so the voxel's
	 * content was placed with a pose close to keyframe i's and i's correction applies to it).
	 * Voxels no lookup passes for are filled by the rigid carry of their source voxels.
	 * 0 = off: every lookup counts (Default: 0.3 m, about one keyframe spacing) */
	double travelWindow{0.3};
	/** Carry source voxels outside every view cone rigidly (Default: true) */
	bool keepVoxelsOutsideCones{true};
	/** At most this many keyframes per corrected 8^3 block [count], 0 = no limit. Kept are those
	 * with the largest (known source voxels their lookups can read in their travel window) x
	 * (weight at the block centre), among those whose cone meets the block. An approximation
	 * that trades F1 for time (measured on the corridor benchmark, doc/maps-3d.md).
	 * (INI morphMaxKeyframesPerBlock; serialized from version 2; Default: 0 = exact) */
	unsigned maxKeyframesPerBlock{0};
	/** Worker threads, 0 = all (Default: 0) */
	unsigned threads{0};
	/** How L_i is read at the earlier position X_i: `nearest` voxel, or `trilinear`
	 * interpolation over the 8 surrounding voxel centres (unknown ones, and those outside the
	 * travel window, left out and the weights renormalised; no value when less than half of the
	 * weight is known). Trilinear avoids the aliasing of nearest lookups on one-voxel-thick
	 * surfaces whose earlier position falls near a voxel boundary, where the nearest voxel is
	 * the free one in front of the surface half of the time (INI morphInterpolation;
	 * Default: trilinear) */
	enum class Interpolation : uint8_t
	{
		Nearest = 0,
		Trilinear = 1
	} interpolation{Interpolation::Trilinear};

	/** The INI keys (prefixed "morph", they share the insertion section), with description and
	 * rule. */
	core::OptionFields fields();
	/** Throws std::invalid_argument naming [section], key and value of the first bad field. */
	void validate(const std::string& section = "insertOpts") const;
};

/** One keyframe as morphing sees it. */
struct MorphKeyframe
{
	uint64_t id{0};
	std::size_t submap{0};  //!< index into the source grids
	double travelled{0};  //!< camera travelled distance when integrated [m]
	core::RgbdCamera camera;  //!< intrinsics for the view cone (distortion ignored there)
	mrpt::poses::CPose3D T_world_cam_old, T_world_cam_new;
};

struct MorphingStats
{
	std::size_t sourceVoxels{0};  //!< known voxels over all source grids
	std::size_t evaluatedVoxels{0};  //!< corrected voxels examined
	std::size_t morphedVoxels{0};  //!< corrected voxels given a weighted average
	std::size_t carriedVoxels{0};  //!< voxels moved rigidly (no value from the cones)
	std::size_t blockKeyframePairs{0};  //!< (corrected block, keyframe) pairs examined
	std::size_t attemptedLookups{0};  //!< (voxel, keyframe) pairs inside the cone, looked up
	std::size_t lookups{0};  //!< (voxel, keyframe) pairs averaged
	double seconds{0};
};

/** Morphs and merges `sources` (all with the same resolution) into one grid in the corrected
 * world frame. Keyframes refer to sources by index. Throws std::invalid_argument on
 * inconsistent input. */
VoxelBlockGrid morphAndMerge(
	const std::vector<const VoxelBlockGrid*>& sources, const std::vector<MorphKeyframe>& keyframes,
	const MorphingOptions& opts, MorphingStats* stats = nullptr);

/** True when the world point p lies in the view cone of a camera at T_world_cam: in front of
 * it, within maxRange of its centre and projecting inside the image (pinhole, no distortion). */
bool insideViewCone(
	const mrpt::math::TPoint3D& p_world, const mrpt::poses::CPose3D& T_world_cam,
	const core::RgbdCamera& cam, double maxRange);

}  // namespace keygrid
