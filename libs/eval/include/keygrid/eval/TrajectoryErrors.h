#pragma once
/** \file TrajectoryErrors.h
 * ATE and RPE of an estimated trajectory against ground truth, as defined by the TUM RGB-D
 * benchmark (Sturm et al. 2012): associate by timestamp, align, and measure.
 */
#include <keygrid/core/TumTrajectory.h>
#include <keygrid/eval/Alignment.h>

#include <optional>
#include <string>

namespace keygrid::eval
{
struct TrajectoryErrorOptions
{
	/** Largest |t_est - t_gt| for a match [s] (Default: 0.02 s, as TUM's tools) */
	double maxDt{0.02};
	/** Align with scale (Sim(3)) instead of SE(3) (Default: false) */
	bool withScale{false};
	/** RPE time step [s] (Default: 1 s, so RPE is per second) */
	double rpeDelta{1.0};
	/** When set, this alignment (estimate frame -> ground-truth frame) is used instead of
	 * the one fitted to the trajectory: errors in a frame fixed beforehand, e.g. a stored map's
	 * frame as the mapping run's alignment gives it (localization is not re-aligned). */
	std::optional<Similarity3> fixedAlignment;

	bool isValid(std::string* error = nullptr) const;
};

/** Summary statistics of a set of errors. */
struct ErrorStats
{
	double rmse{0}, mean{0}, median{0}, stddev{0}, min{0}, max{0};
	std::size_t count{0};
	static ErrorStats Of(std::vector<double> errors);
};

struct TrajectoryErrors
{
	std::size_t gtPoses{0}, estPoses{0}, matched{0};
	Similarity3 alignment;  //!< maps estimated positions into the ground-truth frame
	ErrorStats ate;         //!< absolute trajectory error, translation [m]
	/** Absolute orientation error [deg]: angle(R_gt_k^T R_a R_est_k), with R_a the rotation
	 * closest to sum_k R_gt_k R_est_k^T (chordal mean; unlike the position alignment it is
	 * defined for a camera that does not move). */
	ErrorStats ateRotDeg;
	/** RPE over pose pairs rpeDelta apart, translation [m/s] and rotation [deg/s]; empty when the
	 * matched trajectory is shorter than rpeDelta. */
	std::optional<ErrorStats> rpeTrans, rpeRotDeg;
	double rpeDelta{1.0};

	/** JSON object with keys ate_rmse_m, rpe_trans_m_per_s, rpe_rot_deg_per_s, matched, ... */
	std::string toJson() const;
	/** A few human-readable lines. */
	std::string toText() const;
};

/** The frame of a run's estimate in the ground-truth world: alignPoses() over the poses whose
 * timestamps match within maxDt [s] (orientations and positions, so a camera that turns on
 * the spot still fixes it). A stored map's frame, for measuring a localization run in it
 * (TrajectoryErrorOptions::fixedAlignment). Throws std::invalid_argument when fewer than 3
 * poses match. */
Similarity3 alignTrajectoryPoses(const core::Trajectory& gt, const core::Trajectory& est, double maxDt = 0.02);

/** Evaluates `est` against `gt`. Throws std::invalid_argument when fewer than 3 poses match. */
TrajectoryErrors evaluateTrajectory(
	const core::Trajectory& gt, const core::Trajectory& est, const TrajectoryErrorOptions& opts = {});

}  // namespace keygrid::eval
