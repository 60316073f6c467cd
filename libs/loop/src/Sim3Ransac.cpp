#include "RansacSampling.h"

#include <ceres/ceres.h>
#include <keygrid/loop/Sim3Ransac.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace keygrid::loop
{
void Sim3RansacOptions::validate() const
{
	auto bad = [](const std::string& field, double v, const std::string& rule)
	{ throw std::invalid_argument("Sim3RansacOptions::" + field + " = " + std::to_string(v) + " (must be " + rule + ")"); };
	if (!(inlierChi2 > 0)) bad("inlierChi2", inlierChi2, "positive");
	if (minInliers < 3) bad("minInliers", minInliers, ">= 3");
	if (maxIterations < 1) bad("maxIterations", maxIterations, ">= 1");
	if (!(confidence > 0 && confidence < 1)) bad("confidence", confidence, "in (0, 1)");
	if (refinementRounds < 0) bad("refinementRounds", refinementRounds, ">= 0");
}

namespace
{
template <typename T>
Eigen::Matrix<T, 2, 1> project(const core::PinholeIntrinsics& K, const Eigen::Matrix<T, 3, 1>& p)
{
	return {T(K.fx) * p.x() / p.z() + T(K.cx), T(K.fy) * p.y() / p.z() + T(K.cy)};
}

/** Reprojection error of one match under S_a_b = (q, t, e^logS), in units of the keypoints' sigma:
 *     r_a = (pi(S_a_b p_b) - uv_a) / sigma_a,   r_b = (pi(S_a_b^-1 p_a) - uv_b) / sigma_b
 * with pi the pinhole projection. The map points stay fixed (ORB-SLAM's OptimizeSim3): only the
 * similarity moves, and the two directions make the error symmetric in a and b. The scale is
 * parameterised by its logarithm, so that it stays positive. */
struct Sim3ReprojectionError
{
	Sim3ReprojectionError(const Sim3Match& m, const core::PinholeIntrinsics& K) : m_m(m), m_K(K) {}

	template <typename T>
	bool operator()(const T* q_a_b, const T* t_a_b, const T* logS, T* r) const
	{
		const Sim3T<T> S{Eigen::Map<const Eigen::Quaternion<T>>(q_a_b), Eigen::Map<const Eigen::Matrix<T, 3, 1>>(t_a_b), ceres::exp(logS[0])};
		const Eigen::Matrix<T, 3, 1> pa = S * m_m.p_b.cast<T>();
		const Eigen::Matrix<T, 3, 1> pb = S.inverse() * m_m.p_a.cast<T>();
		const Eigen::Matrix<T, 2, 1> ea = (project(m_K, pa) - m_m.uv_a.cast<T>()) / T(m_m.sigma_a);
		const Eigen::Matrix<T, 2, 1> eb = (project(m_K, pb) - m_m.uv_b.cast<T>()) / T(m_m.sigma_b);
		r[0] = ea.x();
		r[1] = ea.y();
		r[2] = eb.x();
		r[3] = eb.y();
		return true;
	}

	static ceres::CostFunction* Create(const Sim3Match& m, const core::PinholeIntrinsics& K)
	{
		return new ceres::AutoDiffCostFunction<Sim3ReprojectionError, 4, 4, 3, 1>(new Sim3ReprojectionError(m, K));
	}

	Sim3Match m_m;
	core::PinholeIntrinsics m_K;
};

bool isInlier(const Sim3Match& m, const Sim3& S, const core::PinholeIntrinsics& K, double chi2)
{
	const Eigen::Vector2d e2 = sim3ReprojectionErrors(m, S, K);
	return e2[0] < chi2 * m.sigma_a * m.sigma_a && e2[1] < chi2 * m.sigma_b * m.sigma_b;
}

int classify(const std::vector<Sim3Match>& ms, const Sim3& S, const core::PinholeIntrinsics& K, double chi2, std::vector<char>& inlier)
{
	int n = 0;
	for (std::size_t i = 0; i < ms.size(); ++i)
	{
		inlier[i] = isInlier(ms[i], S, K, chi2);
		n += inlier[i];
	}
	return n;
}

/** Umeyama fit of p_a ~= s R p_b + t on three pairs (s = 1 when fixScale); false when they are
 * (near) collinear on either side, as then no rotation is fixed. The test is relative (triangle
 * area against its squared edges): the map's units are arbitrary. */
bool fitMinimal(const std::vector<Sim3Match>& ms, const std::size_t s[3], bool fixScale, Sim3& S)
{
	Eigen::Matrix3d src, dst;
	for (int i = 0; i < 3; ++i)
	{
		src.col(i) = ms[s[i]].p_b;
		dst.col(i) = ms[s[i]].p_a;
	}
	for (const Eigen::Matrix3d* P : {&src, &dst})
	{
		const Eigen::Vector3d e1 = P->col(1) - P->col(0), e2 = P->col(2) - P->col(0);
		const double edges = e1.squaredNorm() + e2.squaredNorm() + (e2 - e1).squaredNorm();
		if (!(e1.cross(e2).norm() > 1e-3 * edges)) return false;
	}
	const Eigen::Matrix4d T = Eigen::umeyama(src, dst, !fixScale);
	if (!T.allFinite()) return false;
	const double scale = T.topLeftCorner<3, 3>().col(0).norm();
	if (!(scale > 0)) return false;
	S = Sim3{Eigen::Quaterniond(Eigen::Matrix3d(T.topLeftCorner<3, 3>() / scale)).normalized(), T.topRightCorner<3, 1>(), fixScale ? 1.0 : scale};
	return true;
}

/** Minimises the matches' reprojection errors over S (Huber loss at the inlier threshold); the
 * scale stays that of S0 when fixScale. */
Sim3 refine(const std::vector<Sim3Match>& ms, const std::vector<char>& inlier, const Sim3& S0, const core::PinholeIntrinsics& K, double chi2, bool fixScale)
{
	Eigen::Quaterniond q = S0.q;
	Eigen::Vector3d t = S0.t;
	double logS = std::log(S0.s);
	ceres::Problem problem;
	for (std::size_t i = 0; i < ms.size(); ++i)
		if (inlier[i])
			problem.AddResidualBlock(Sim3ReprojectionError::Create(ms[i], K), new ceres::HuberLoss(std::sqrt(chi2)), q.coeffs().data(), t.data(), &logS);
	problem.SetManifold(q.coeffs().data(), new ceres::EigenQuaternionManifold());
	if (fixScale) problem.SetParameterBlockConstant(&logS);
	ceres::Solver::Options o;
	o.linear_solver_type = ceres::DENSE_QR;
	o.max_num_iterations = 10;
	o.num_threads = 1;
	ceres::Solver::Summary summary;
	ceres::Solve(o, &problem, &summary);
	const Sim3 S{q.normalized(), t, std::exp(logS)};
	if (!summary.IsSolutionUsable() || !S.t.allFinite() || !std::isfinite(S.s) || !(S.s > 0)) return S0;
	return S;
}
}  // namespace

Eigen::Vector2d sim3ReprojectionErrors(const Sim3Match& m, const Sim3& S_a_b, const core::PinholeIntrinsics& K)
{
	constexpr double inf = std::numeric_limits<double>::infinity();
	const Eigen::Vector3d pa = S_a_b * m.p_b;
	const Eigen::Vector3d pb = S_a_b.inverse() * m.p_a;
	return {pa.z() > 0 ? (project(K, pa) - m.uv_a).squaredNorm() : inf, pb.z() > 0 ? (project(K, pb) - m.uv_b).squaredNorm() : inf};
}

Sim3RansacResult estimateSim3Ransac(const std::vector<Sim3Match>& ms, const core::PinholeIntrinsics& K, const Sim3RansacOptions& opts)
{
	opts.validate();
	Sim3RansacResult res;
	const std::size_t n = ms.size();
	res.inlier.assign(n, 0);
	if (n < 3) return res;

	std::vector<char> inl(n);
	Sim3 best;
	int bestCount = 0;
	res.iterations = detail::runRansacHypotheses(
		opts.seed, n, opts.maxIterations, opts.confidence,
		[&](const std::size_t s[3]) -> std::optional<int>
		{
			Sim3 S;
			if (!fitMinimal(ms, s, opts.fixScale, S)) return std::nullopt;
			const int count = classify(ms, S, K, opts.inlierChi2, inl);
			if (count <= bestCount) return std::nullopt;
			bestCount = count;
			best = S;
			return count;
		});
	if (bestCount < 3) return res;

	// Refinement by reprojection on the inliers, re-classified after each round.
	int count = classify(ms, best, K, opts.inlierChi2, inl);
	for (int r = 0; r < opts.refinementRounds && count >= 3; ++r)
	{
		best = refine(ms, inl, best, K, opts.inlierChi2, opts.fixScale);
		count = classify(ms, best, K, opts.inlierChi2, inl);
	}
	res.S_a_b = best;
	res.inlier = inl;
	res.numInliers = count;
	res.success = count >= opts.minInliers;
	return res;
}

}  // namespace keygrid::loop
