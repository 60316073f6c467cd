#include <keygrid/sfm/PoseOptimizer.h>
#include <mrpt/math/CMatrixFixed.h>

#include <ceres/ceres.h>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

namespace keygrid::sfm
{
namespace
{
/** Pose-only form of AnalyticReprojectionCost (hand-written Jacobians, see
 * RgbdReprojectionCost.h): the point is a constant. Parameters q_cam_world (x,y,z,w) and
 * t_cam_world; 3 residuals, the third one 0 without depth. */
class AnalyticPoseCost final : public ceres::SizedCostFunction<3, 4, 3>
{
   public:
	AnalyticPoseCost(const AnalyticReprojectionCost& c, const Eigen::Vector3d& p_world) : m_cost(c), m_p(p_world) {}
	bool Evaluate(double const* const* x, double* r, double** J) const override
	{
		return m_cost.evaluate(x[0], x[1], m_p.data(), r, J ? J[0] : nullptr, J ? J[1] : nullptr, nullptr);
	}

   private:
	AnalyticReprojectionCost m_cost;
	Eigen::Vector3d m_p;
};

// chi2 of an observation whose point is not in front of the camera (never an inlier).
constexpr double kBehindCamera = 1e30;

bool usesDepth(const PoseObservation& ob, const PoseOptimizerOptions& o) { return ob.depth > 0 && ob.depth < o.maxDepthForRgbd; }

/** Squared residual of one observation at (q, t) = T_cam_world (no robust loss). */
double chi2At(const double q[4], const double t[3], const PoseObservation& ob, const PinholeIntrinsics& K, const PoseOptimizerOptions& o)
{
	double u, v, ur;
	const double p[3] = {ob.p_world.x(), ob.p_world.y(), ob.p_world.z()};
	if (!projectRgbd(q, t, p, K, o.bf, u, v, ur)) return kBehindCamera;
	const double du = (ob.uv.x() - u) * ob.invSigma, dv = (ob.uv.y() - v) * ob.invSigma;
	double e = du * du + dv * dv;
	if (usesDepth(ob, o))
	{
		const double dr = (o.bf / ob.depth - (u - ur)) / o.disparitySigma;  // u - ur = bf / z
		e += dr * dr;
	}
	return e;
}
}  // namespace

double inlierThreshold(const PoseObservation& ob, const PoseOptimizerOptions& o) { return usesDepth(ob, o) ? o.chi2Rgbd : o.chi2Mono; }

double observationChi2(const mrpt::poses::CPose3D& T_world_cam, const PoseObservation& ob, const PinholeIntrinsics& K, const PoseOptimizerOptions& o)
{
	double q[4], t[3];
	toCeres(T_world_cam, q, t);
	const double e = chi2At(q, t, ob, K, o);
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
	double q[4], t[3];
	toCeres(T_world_cam, q, t);
	std::vector<PoseObservation> kept;
	std::vector<std::size_t> keptIndex;
	for (std::size_t i = 0; i < obs.size(); i++)
		if (isAnchor[i] || chi2At(q, t, obs[i], K, o) <= chi2Factor * inlierThreshold(obs[i], o))
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
	double q[4], t[3];
	toCeres(T_world_cam, q, t);
	const std::size_t n = obs.size();
	PoseOptimizerResult res;
	res.inlier.assign(n, 1);

	auto useDepth = [&](const PoseObservation& ob) { return usesDepth(ob, o); };
	auto chi2 = [&](const PoseObservation& ob) { return chi2At(q, t, ob, K, o); };

	// A point behind the camera at the initial pose would make Ceres stop at its first
	// evaluation: such observations start as outliers (they may come back after a round).
	for (std::size_t i = 0; i < n; i++) res.inlier[i] = chi2(obs[i]) < kBehindCamera;

	ceres::Solver::Options so;
	so.linear_solver_type = ceres::DENSE_QR;
	so.max_num_iterations = o.iterationsPerRound;
	so.num_threads = 1;
	so.logging_type = ceres::SILENT;
	so.minimizer_progress_to_stdout = false;

	// One Huber loss per observation kind, shared by all residual blocks of a round.
	ceres::HuberLoss huberRgbd(std::sqrt(o.chi2Rgbd)), huberMono(std::sqrt(o.chi2Mono));
	for (int round = 0; round < o.rounds; round++)
	{
		ceres::Problem::Options po;
		po.manifold_ownership = ceres::TAKE_OWNERSHIP;
		po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
		ceres::Problem problem(po);
		problem.AddParameterBlock(q, 4, new ceres::EigenQuaternionManifold());
		problem.AddParameterBlock(t, 3);
		int used = 0;
		for (std::size_t i = 0; i < n; i++)
		{
			if (!res.inlier[i]) continue;
			const auto& ob = obs[i];
			// Huber only in the first rounds: later rounds see inliers only (as ORB-SLAM2).
			ceres::LossFunction* loss = nullptr;
			if (round < o.rounds - 1) loss = useDepth(ob) ? &huberRgbd : &huberMono;
			const AnalyticReprojectionCost cost(ob.uv, useDepth(ob) ? ob.depth : 0.0, o.bf, ob.invSigma, 1.0 / o.disparitySigma, K);
			problem.AddResidualBlock(new AnalyticPoseCost(cost, ob.p_world), loss, q, t);
			++used;
		}
		if (used < 3) break;
		ceres::Solver::Summary summary;
		ceres::Solve(so, &problem, &summary);
		// Re-classify every observation (outliers may come back) at the new estimate.
		for (std::size_t i = 0; i < n; i++)
			res.inlier[i] = chi2(obs[i]) <= (useDepth(obs[i]) ? o.chi2Rgbd : o.chi2Mono);
	}
	res.inliers = 0;
	double sq = 0;
	for (std::size_t i = 0; i < n; i++)
	{
		if (!res.inlier[i]) continue;
		res.inliers++;
		double u, v, ur;
		const double p[3] = {obs[i].p_world.x(), obs[i].p_world.y(), obs[i].p_world.z()};
		projectRgbd(q, t, p, K, o.bf, u, v, ur);
		sq += (obs[i].uv - Eigen::Vector2d(u, v)).squaredNorm();
	}
	res.rmsPixels = res.inliers ? std::sqrt(sq / res.inliers) : 0.0;
	T_world_cam = fromCeres(q, t);
	return res;
}

}  // namespace keygrid::sfm
