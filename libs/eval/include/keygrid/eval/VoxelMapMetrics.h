#pragma once
/** \file VoxelMapMetrics.h
 * Accuracy of an estimated 3D occupancy map (occupied and free voxels, e.g. keygrid-slam's
 * map_3d.bt) against ground-truth occupied voxels (e.g. keygrid-sim's occupancy_voxels.txt), the
 * map carried into the ground-truth world by a similarity (keygrid-eval's trajectory alignment):
 * * precision: the map's occupied voxels with a true occupied voxel within the tolerance;
 * * recall: the true occupied voxels with a map occupied voxel within the tolerance, over all of
 *   them and over those the cameras saw (VoxelTruth::markSeen);
 * * free-space errors: true occupied voxels the map calls free, and of those the hazards, with no
 *   map occupied voxel within the tolerance either (the 3D analogue of the 2D grid's hazard
 *   cells: an obstacle the map has nowhere near where it says free).
 * Distances are measured on the ground truth's lattice: a map voxel counts at the true voxel its
 * centre falls in, and two voxels match when their centres are at most the tolerance apart
 * (a tolerance of one voxel size: the voxel and its 6 face neighbours).
 * Plain voxel lists, so the simulator's and the maps' types stay out of libs/eval.
 */
#include <keygrid/eval/Alignment.h>

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

namespace keygrid::eval
{
using VoxelIndex = std::array<int32_t, 3>;

/** An estimated map: voxel (i, j, k) covers [i res, (i+1) res) per axis of the map's frame. */
struct VoxelMapEstimate
{
	/** Voxel size [m] (Default: 0.05) */
	double resolution{0.05};
	std::vector<VoxelIndex> occupied, free;
};

/** Ground-truth occupied voxels: voxel (i, j, k) covers [origin + i res, origin + (i+1) res) per
 * axis of the ground-truth world; which of them the cameras saw. */
class VoxelTruth
{
   public:
	/** Throws std::invalid_argument on resolution <= 0. Duplicates are dropped. */
	VoxelTruth(double resolution, const Eigen::Vector3d& origin, const std::vector<VoxelIndex>& occupied);

	double resolution() const { return m_res; }
	const Eigen::Vector3d& origin() const { return m_origin; }
	const std::vector<VoxelIndex>& occupied() const { return m_voxels; }
	VoxelIndex indexOf(const Eigen::Vector3d& p_world) const;
	Eigen::Vector3d centre(const VoxelIndex& v) const;
	/** Position of voxel v in occupied(), or -1. */
	long find(const VoxelIndex& v) const;

	/** Marks as seen the true voxels a surface point p_world (e.g. of a rendered depth image)
	 * lies in; a point on a voxel face (to a small margin) marks the voxels on both sides
	 * (surfaces that lie on voxel faces). Returns how many true voxels it marked (new or not). */
	int markSeen(const Eigen::Vector3d& p_world);
	/** Whether any voxel was marked: without marks every voxel counts as seen. */
	bool hasSeenMask() const { return m_anySeen; }
	bool seen(std::size_t i) const { return !m_anySeen || m_seen[i]; }

   private:
	double m_res;
	Eigen::Vector3d m_origin;
	std::vector<VoxelIndex> m_voxels;
	std::unordered_map<uint64_t, std::size_t> m_lookup;
	std::vector<uint8_t> m_seen;
	bool m_anySeen{false};
};

struct VoxelMapMetricsOptions
{
	/** Two voxels match when their centres are at most this far apart [m]; one voxel size
	 * matches face neighbours (Default: 0.05 m) */
	double matchTolerance{0.05};

	bool isValid(std::string* error = nullptr) const;
};

struct VoxelMapMetrics
{
	/** The map's occupied voxels, and those with a true occupied voxel within the tolerance. */
	std::size_t estOccupied{0}, estOccupiedMatched{0};
	/** The map's free voxels. */
	std::size_t estFree{0};
	double precision{0};
	/** True occupied voxels, and those with a map occupied voxel within the tolerance. */
	std::size_t gtOccupied{0}, gtOccupiedMatched{0};
	double recall{0};
	/** The same over the true voxels the cameras saw (all of them without a seen mask). */
	std::size_t gtSeen{0}, gtSeenMatched{0};
	double seenRecall{0};
	/** True occupied voxels whose centre lies in a voxel the map calls free; hazardVoxels: those
	 * of them with no map occupied voxel within the tolerance. */
	std::size_t gtCalledFree{0}, hazardVoxels{0};

	/** Human-readable lines. */
	std::string toText() const;
	/** `"<prefix>...": value` lines (no braces) for a JSON object: occupied_voxels,
	 * occupied_matched, free_voxels, precision, true_voxels, recall, true_voxels_seen,
	 * recall_seen, true_called_free, hazard_voxels. */
	std::string jsonFields(const std::string& prefix) const;
};

/** Scores `est` against `truth`; T_gt_map maps the map's frame into the ground-truth world (scale
 * included: a Sim(3) alignment scales the map's voxels). Throws std::invalid_argument on invalid
 * options or a map resolution <= 0. */
VoxelMapMetrics evaluateVoxelMap(
	const VoxelMapEstimate& est, const Similarity3& T_gt_map, const VoxelTruth& truth, const VoxelMapMetricsOptions& opts = {});

}  // namespace keygrid::eval
