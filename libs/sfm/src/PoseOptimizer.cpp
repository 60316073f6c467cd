#include <keygrid/sfm/PoseOptimizer.h>
#include <mrpt/math/CMatrixFixed.h>

#include <keygrid/sfm/PoseLevenbergMarquardt.h>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace keygrid::sfm
{
namespace
{
// chi2 of an observation whose point is not in front of the camera (never an inlier).
constexpr double kBehindCamera = 1e30;

bool usesDepth(const PoseObservation& ob, const PoseOptimizerOptions& o) { return ob.depth > 0 && ob.depth < o.maxDepthForRgbd; }

/** One observation as a residual term of the pose solver (no robust loss). */
PoseResidualTerm residualTerm(const PoseObservation& ob, const PoseOptimizerOptions& o)
{
	PoseResidualTerm term;
	term.p_world = ob.p_world;
	term.uv = ob.uv;
	term.invSigma = ob.invSigma;
	if (usesDepth(ob, o))
	{
		term.disparity = o.bf / ob.depth;
		term.invSigmaDisparity = 1.0 / o.disparitySigma;
	}
	return term;
}

/** (R, t) = T_cam_world of the camera pose T_world_cam. */
void cameraFromWorld(const mrpt::poses::CPose3D& T_world_cam, Eigen::Matrix3d& R, Eigen::Vector3d& t)
{
	double q[4], tq[3];
	toCeres(T_world_cam, q, tq);
	R = Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized().toRotationMatrix();
	t = Eigen::Vector3d(tq[0], tq[1], tq[2]);
}

/** Squared residual of a term at (R, t) = T_cam_world (no robust loss); kBehindCamera when the
 * point is not in front of the camera. */
double chi2At(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const PoseResidualTerm& term, const PinholeIntrinsics& K, const PoseOptimizerOptions& o)
{
	double e;
	return poseResidualSquaredNorm(R, t, term, K, o.bf, e) ? e : kBehindCamera;
}
}  // namespace

double inlierThreshold(const PoseObservation& ob, const PoseOptimizerOptions& o) { return usesDepth(ob, o) ? o.chi2Rgbd : o.chi2Mono; }

double observationChi2(const mrpt::poses::CPose3D& T_world_cam, const PoseObservation& ob, const PinholeIntrinsics& K, const PoseOptimizerOptions& o)
{
	Eigen::Matrix3d R;
	Eigen::Vector3d t;
	cameraFromWorld(T_world_cam, R, t);
	const double e = chi2At(R, t, residualTerm(ob, o), K, o);
	return e >= kBehindCamera ? std::numeric_limits<double>::infinity() : e;
}

PoseOptimizerResult optimizePoseAnchored(
	mrpt::poses::CPose3D& T_world_cam, const std::vector<PoseObservation>& obs, const std::vector<char>& isAnchor,
	const PinholeIntrinsics& K, const PoseOptimizerOptions& o, double chi2Factor, int minAnchors, int* rejected)
{
	if (isAnchor.size() != obs.size()) throw std::invalid_argument("optimizePoseAnchored: isAnchor and obs differ in size");
	if (rejected) *rejected = 0;
	std::vector<PoseObservation> anchors;
	for (std::size_t i = 0; i < obs.size(); i++)
		if (isAnchor[i]) anchors.push_back(obs[i]);
	if (static_cast<int>(anchors.size()) < std::max(minAnchors, 3)) return optimizePose(T_world_cam, obs, K, o);
	optimizePose(T_world_cam, anchors, K, o);
	Eigen::Matrix3d R;
	Eigen::Vector3d t;
	cameraFromWorld(T_world_cam, R, t);
	std::vector<PoseObservation> kept;
	std::vector<std::size_t> keptIndex;
	for (std::size_t i = 0; i < obs.size(); i++)
		if (isAnchor[i] || chi2At(R, t, residualTerm(obs[i], o), K, o) <= chi2Factor * inlierThreshold(obs[i], o))
		{
			kept.push_back(obs[i]);
			keptIndex.push_back(i);
		}
	if (rejected) *rejected = static_cast<int>(obs.size() - kept.size());
	const auto r = optimizePose(T_world_cam, kept, K, o);
	PoseOptimizerResult res;
	res.inlier.assign(obs.size(), 0);
	for (std::size_t k = 0; k < kept.size(); k++) res.inlier[keptIndex[k]] = r.inlier[k];
	res.inliers = r.inliers;
	res.rmsPixels = r.rmsPixels;
	return res;
}

void toCeres(const mrpt::poses::CPose3D& T_world_cam, double q[4], double t[3])
{
	const auto T_cam_world = -T_world_cam;
	const auto R = T_cam_world.getRotationMatrix();
	Eigen::Matrix3d Re;
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++) Re(i, j) = R(i, j);
	Eigen::Quaterniond qe(Re);
	qe.normalize();
	q[0] = qe.x();
	q[1] = qe.y();
	q[2] = qe.z();
	q[3] = qe.w();
	t[0] = T_cam_world.x();
	t[1] = T_cam_world.y();
	t[2] = T_cam_world.z();
}

mrpt::poses::CPose3D fromCeres(const double q[4], const double t[3])
{
	const Eigen::Quaterniond qe(q[3], q[0], q[1], q[2]);
	const Eigen::Matrix3d Re = qe.normalized().toRotationMatrix();
	mrpt::math::CMatrixDouble33 R;
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++) R(i, j) = Re(i, j);
	mrpt::math::CVectorFixedDouble<3> tv;
	tv[0] = t[0];
	tv[1] = t[1];
	tv[2] = t[2];
	const mrpt::poses::CPose3D T_cam_world = mrpt::poses::CPose3D::FromRotationAndTranslation(R, tv);
	return -T_cam_world;
}

PoseOptimizerResult optimizePose(
	mrpt::poses::CPose3D& T_world_cam, const std::vector<PoseObservation>& obs,
	const PinholeIntrinsics& K, const PoseOptimizerOptions& o)
{
	if (obs.empty()) throw std::invalid_argument("optimizePose: no observations");
	if (!(o.disparitySigma > 0)) throw std::invalid_argument("optimizePose: disparitySigma must be > 0");
	Eigen::Matrix3d R;
	Eigen::Vector3d t;
	cameraFromWorld(T_world_cam, R, t);
	const std::size_t n = obs.size();

	// Each observation as a residual term; the Huber threshold is set per round.
	std::vector<PoseResidualTerm> all(n);
	for (std::size_t i = 0; i < n; i++) all[i] = residualTerm(obs[i], o);
	const auto chi2 = [&](std::size_t i) { return chi2At(R, t, all[i], K, o); };

	PoseOptimizerResult res;
	res.inlier.assign(n, 1);
	// A point behind the camera at the initial pose would stop the solve at its first
	// evaluation: such observations start as outliers (they may come back after a round).
	for (std::size_t i = 0; i < n; i++) res.inlier[i] = chi2(i) < kBehindCamera;

	PoseSolverOptions so;
	so.maxIterations = o.iterationsPerRound;
	std::vector<PoseResidualTerm> used;
	used.reserve(n);
	for (int round = 0; round < o.rounds; round++)
	{
		used.clear();
		for (std::size_t i = 0; i < n; i++)
		{
			if (!res.inlier[i]) continue;
			used.push_back(all[i]);
			// Huber only in the first rounds: later rounds see inliers only (as ORB-SLAM2).
			used.back().huberDelta = round < o.rounds - 1 ? std::sqrt(inlierThreshold(obs[i], o)) : 0.0;
		}
		if (used.size() < 3) break;
		solvePoseLevenbergMarquardt(R, t, used, K, o.bf, so);
		// Re-classify every observation (outliers may come back) at the new estimate.
		for (std::size_t i = 0; i < n; i++) res.inlier[i] = chi2(i) <= inlierThreshold(obs[i], o);
	}
	res.inliers = 0;
	double sq = 0;
	for (std::size_t i = 0; i < n; i++)
	{
		if (!res.inlier[i]) continue;
		res.inliers++;
		PoseResidualTerm uvOnly = all[i];
		uvOnly.invSigma = 1.0;
		uvOnly.disparity = 0;
		double e = 0;
		poseResidualSquaredNorm(R, t, uvOnly, K, o.bf, e);
		sq += e;
	}
	res.rmsPixels = res.inliers ? std::sqrt(sq / res.inliers) : 0.0;
	const Eigen::Quaterniond qr(R);
	const double qOut[4] = {qr.x(), qr.y(), qr.z(), qr.w()};
	T_world_cam = fromCeres(qOut, t.data());
	return res;
}

}  // namespace keygrid::sfm
