#pragma once
/** \file DepthFrameIntegrator.h
 * Integration of a whole depth frame into a VoxelBlockGrid, in two steps so that the map can
 * look at what a frame would change before changing anything (conflict detection):
 *  1. castFrame(): a 3D DDA ray (Dda.h) from the camera centre through every (decimated) pixel,
 *     collected into a FrameVoxelUpdates set in which every voxel appears once, either "hit"
 *     (the ray ended there) or "free" (a ray passed through). Occupied wins: a voxel that is
 *     the end of one ray and crossed by another is a hit. The rays are cast by several threads
 *     into a shared per-frame mark volume with atomic OR, so the result does not depend on the
 *     thread interleaving.
 *  2. apply(): one log-odds update per voxel of that set (clamped), plus the travelled distance.
 *
 * Conventions match OctoMap's insertPointCloud: the voxel holding the measured point is
 * occupied, the voxels strictly before it are free; a ray longer than maxRange is cut at
 * maxRange and only marks free voxels (strictly before the cut voxel). With
 * discretizeEndpoints (the default, = OctoMap's discretize=true) one ray is cast per distinct
 * end voxel, to its centre; otherwise one per pixel.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>
#include <keygrid/core/RgbdCamera.h>
#include <keygrid/maps/VoxelBlockGrid.h>
#include <mrpt/poses/CPose3D.h>
#include <opencv2/core/mat.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace keygrid
{
/** Parameters of depth-frame integration. */
struct DepthIntegrationOptions : public core::FieldTableOptions<DepthIntegrationOptions>
{
	/** Rays are cut at this Euclidean range from the camera centre [m] (Default: 4 m) */
	double maxRange{4.0};
	/** Pixels whose range is below this are ignored [m] (Default: 0.1 m) */
	double minRange{0.1};
	/** Use every N-th pixel in u and v (Default: 1 = every pixel) */
	unsigned pixelDecimation{1};
	/** Worker threads, 0 = all hardware threads (Default: 0) */
	unsigned threads{0};
	/** Log-odds added to a hit voxel (Default: 0.85 = logit(0.7), OctoMap's prob_hit) */
	float logOddsHit{0.85f};
	/** Log-odds added to a free voxel, negative (Default: -0.4 = logit(0.4), OctoMap's
	 * prob_miss) */
	float logOddsMiss{-0.4f};
	/** Lower clamp of the log-odds (Default: -2.0 = logit(0.12), OctoMap's clamping_thres_min) */
	float logOddsMin{-2.0f};
	/** Upper clamp of the log-odds (Default: 3.5 = logit(0.97), OctoMap's clamping_thres_max) */
	float logOddsMax{3.5f};
	/** Cast one ray per distinct end voxel (to the voxel centre) instead of one per pixel.
	 * Every pixel still contributes its end voxel (hit / cut), only the free-space rays are
	 * shared, exactly like OctoMap's insertPointCloud(..., discretize = true). A 640x480 Kinect
	 * frame at 5 cm has ~5-10 k distinct end voxels for ~230 k valid pixels, so this is ~30x
	 * less ray casting; the carved free space differs from per-pixel rays only at the rim of
	 * thin rays between neighbouring end voxels (Default: true) */
	bool discretizeEndpoints{true};
	/** Largest dense per-frame mark volume [voxels, 1 byte each], in [512, 2^30] (memory);
	 * frames whose bounding box is larger use a slower sparse path (Default: 64 Mi voxels =
	 * 64 MB) */
	double maxDenseMarkVoxels{64.0 * 1024 * 1024};

	/** The INI keys, with description and rule. */
	core::OptionFields fields();
	/** Throws std::invalid_argument naming [section], key and value of the first bad field. */
	void validate(const std::string& section = "insertOpts") const;
};

/** The voxels one frame updates, each once, grouped by block. */
class FrameVoxelUpdates
{
   public:
	enum Mark : uint8_t
	{
		kNone = 0,
		kFree = 1,
		kHit = 2
	};
	/** Marks of the 8^3 voxels of one block (VoxelBlock layout); kHit bit wins over kFree. */
	struct Chunk
	{
		VoxelIndex block;
		std::array<uint8_t, VoxelBlock::kVoxels> marks{};
	};

	double resolution{0.05};
	/** Deterministically ordered (by block index) chunks that have at least one mark. */
	std::vector<Chunk> chunks;
	/** Valid pixels / points, and of voxels marked free / hit. */
	std::size_t rays{0}, freeVoxels{0}, hitVoxels{0};
	/** Rays actually traversed (= rays, or the distinct end voxels when discretizing). */
	std::size_t castRays{0};
	/** Total voxel visits over all rays (before duplicate suppression). */
	std::size_t voxelVisits{0};
	/** True when the sparse path was used (bounding box too big for the dense volume). */
	bool sparsePath{false};

	static bool isHit(uint8_t m) { return (m & kHit) != 0; }
	std::size_t numUpdates() const { return freeVoxels + hitVoxels; }
};

/** Per-pixel unit-depth ray directions (x/z, y/z) of a camera, with lens distortion removed,
 * cached for the integrator (computing them with cv::undistortPoints per frame would cost more
 * than the ray casting). */
class PixelRayTable
{
   public:
	/** Rebuilds the table when the camera differs from the cached one. */
	void update(const core::RgbdCamera& cam);
	/** Normalised coordinates of pixel (u, v): the ray is (x, y, 1) * depth in the camera frame. */
	const float* row(unsigned v) const { return &m_xy[2 * static_cast<std::size_t>(v) * m_w]; }
	unsigned width() const { return m_w; }
	unsigned height() const { return m_h; }

   private:
	core::RgbdCamera m_cam;
	bool m_valid{false};
	unsigned m_w{0}, m_h{0};
	std::vector<float> m_xy;
};

/** Casts depth frames into FrameVoxelUpdates and applies them to a grid. Holds only caches
 * (ray table, scratch memory), so use one integrator per calling thread (it uses its own
 * worker threads inside each call). */
class DepthFrameIntegrator
{
   public:
	explicit DepthFrameIntegrator(const DepthIntegrationOptions& opts);

	const DepthIntegrationOptions& options() const { return m_opts; }
	/** An end voxel of the discretized mode; hit = false for rays cut at maxRange. */
	struct EndVoxel
	{
		VoxelIndex v;
		bool hit;
	};

	/** Replaces the options (validated), keeping the caches. */
	void setOptions(const DepthIntegrationOptions& opts)
	{
		opts.validate();
		m_opts = opts;
	}

	/** Ray-casts a depth image [m] (CV_32FC1, 0 or NaN = invalid) seen by `cam` at pose
	 * T_world_cam (optical frame: x right, y down, z forward) on a grid of `resolution` [m]. */
	FrameVoxelUpdates castFrame(
		const cv::Mat& depth_m, const core::RgbdCamera& cam,
		const mrpt::poses::CPose3D& T_world_cam, double resolution);

	/** Ray-casts explicit end points [m, world] from one origin (OctoMap-style point clouds).
	 * A point farther than maxRange is cut at maxRange and is not a hit. */
	FrameVoxelUpdates castPoints(
		const mrpt::math::TPoint3D& origin_world, const std::vector<mrpt::math::TPoint3Df>& pts,
		double resolution);

	/** Applies the log-odds updates of `upd` to `grid` and stamps every updated voxel with the
	 * camera's travelled distance [m]. Throws when the resolutions differ. */
	void apply(VoxelBlockGrid& grid, const FrameVoxelUpdates& upd, double travelled) const;

   private:
	/** Bounding box (voxels) of the origin and the ray ends, and the number of rays. */
	struct Extent
	{
		VoxelIndex lo, hi;
		std::size_t rays{0};
		void add(const VoxelIndex& v)
		{
			lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
			hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
		}
		void merge(const Extent& e)
		{
			add(e.lo);
			add(e.hi);
			rays += e.rays;
		}
	};
	/** Casts the rays: with discretizeEndpoints the end voxels in m_runs (one list per worker,
	 * runs of equal voxels collapsed), else the n points of m_ends with m_flags (0 invalid,
	 * 1 cut at maxRange, 2 hit). */
	FrameVoxelUpdates castRays(
		const mrpt::math::TPoint3D& origin, std::size_t n, const Extent& extent, double resolution);

	DepthIntegrationOptions m_opts;
	PixelRayTable m_rays;
	/** Per-frame scratch reused between frames (so one integrator serves one thread): ray ends
	 * (world points or voxels), their flags and the mark volume. */
	std::vector<mrpt::math::TPoint3Df> m_ends;
	std::vector<std::vector<EndVoxel>> m_runs;
	std::vector<uint8_t> m_flags;
	std::vector<uint8_t> m_marks;
};

}  // namespace keygrid
