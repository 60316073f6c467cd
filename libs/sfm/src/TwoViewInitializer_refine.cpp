// TwoViewInitializer, refinement of the accepted motion: the linear estimates (8-point,
// DLT) are algebraic, several times less accurate than the noise allows; a few
// Levenberg-Marquardt steps on the Sampson error bring the motion close to the
// maximum-likelihood one before the points are triangulated for the map.
#include <Eigen/Dense>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

#include "TwoViewInitializerDetail.h"

namespace keygrid::sfm::detail
{
namespace
{
using Vector5d = Eigen::Matrix<double, 5, 1>;

/** The motion at parameters p = (w, a) around m: R = exp([w]_x) R_m, t = normalise(t_m + B a)
 * with B an orthonormal basis of the plane orthogonal to t_m (the unit sphere's tangent: the
 * scale of t is the gauge, fixed at 1). */
RelativeMotion perturb(const RelativeMotion& m, const Eigen::Matrix<double, 3, 2>& B, const Vector5d& p)
{
	const Eigen::Vector3d w = p.head<3>();
	const double angle = w.norm();
	const Eigen::Matrix3d dR = angle > 0 ? Eigen::AngleAxisd(angle, w / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
	return {dR * m.R_cur_ref, (m.t_cur_ref + B * p.tail<2>()).normalized()};
}

/* Sampson error of pair i under F = K^-T [t]_x R K^-1 (pixels): the first-order distance of
 * (x_ref, x_cur) to the variety x_cur^T F x_ref = 0,
 *   r = x_cur^T F x_ref / sqrt(s_cur^2 ((F x_ref)_1^2 + (F x_ref)_2^2) + s_ref^2 ((F^T x_cur)_1^2 + (F^T x_cur)_2^2)),
 * with the per-view stds s, so r ~ N(0, 1) and sum r^2 is the (first-order) negative
 * log-likelihood of the motion with the points eliminated. */
Eigen::VectorXd sampson(const RelativeMotion& m, const Eigen::Matrix3d& Kinv, const WeightedMatches& w, const std::vector<int>& idx)
{
	Eigen::Matrix3d tx;
	const Eigen::Vector3d& t = m.t_cur_ref;
	tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
	const Eigen::Matrix3d F = Kinv.transpose() * tx * m.R_cur_ref * Kinv;
	Eigen::VectorXd r(idx.size());
	for (std::size_t k = 0; k < idx.size(); k++)
	{
		const auto i = static_cast<std::size_t>(idx[k]);
		const Eigen::Vector3d a(w.m->px_ref[i].x(), w.m->px_ref[i].y(), 1.0), b(w.m->px_cur[i].x(), w.m->px_cur[i].y(), 1.0);
		const Eigen::Vector3d Fa = F * a, Ftb = F.transpose() * b;
		const double den = Fa.head<2>().squaredNorm() / w.invVarCur[i] + Ftb.head<2>().squaredNorm() / w.invVarRef[i];
		r(static_cast<Eigen::Index>(k)) = den > 0 ? b.dot(Fa) / std::sqrt(den) : 0.0;
	}
	return r;
}

/** Levenberg-Marquardt on the Sampson error of the pairs idx (at most 20 iterations). */
RelativeMotion minimiseSampson(const RelativeMotion& start, const Eigen::Matrix3d& Kinv, const WeightedMatches& w, const std::vector<int>& idx)
{
	if (idx.size() < 5) return start;
	RelativeMotion m = start;
	double cost = sampson(m, Kinv, w, idx).squaredNorm();
	double lambda = 1e-6;  // Levenberg damping, relative to the diagonal
	for (int it = 0; it < 20; it++)
	{
		Eigen::Matrix<double, 3, 2> B;
		B.col(0) = m.t_cur_ref.unitOrthogonal();
		B.col(1) = m.t_cur_ref.cross(B.col(0));
		const Eigen::VectorXd r = sampson(m, Kinv, w, idx);
		// Central differences: the residuals are smooth and 10 evaluations of a few hundred
		// pairs cost less than writing the analytic Jacobian of the normalised Sampson form.
		Eigen::MatrixXd J(r.size(), 5);
		const double h = 1e-7;
		for (int k = 0; k < 5; k++)
		{
			Vector5d d = Vector5d::Zero();
			d(k) = h;
			J.col(k) = (sampson(perturb(m, B, d), Kinv, w, idx) - sampson(perturb(m, B, -d), Kinv, w, idx)) / (2 * h);
		}
		const Eigen::Matrix<double, 5, 5> JtJ = J.transpose() * J;
		const Vector5d g = J.transpose() * r;
		bool improved = false;
		for (int tries = 0; tries < 10; tries++)
		{
			Eigen::Matrix<double, 5, 5> A = JtJ;
			A.diagonal() *= 1.0 + lambda;
			const RelativeMotion cand = perturb(m, B, -A.ldlt().solve(g));
			const double c = sampson(cand, Kinv, w, idx).squaredNorm();
			if (c < cost)
			{
				const bool converged = cost - c < 1e-10 * cost;
				improved = true;
				m = cand;
				cost = c;
				lambda = std::max(1e-9, lambda / 10);
				if (converged) return m;
				break;
			}
			lambda *= 10;
		}
		if (!improved) break;
	}
	return m;
}
}  // namespace

RelativeMotion refineMotion(
	const RelativeMotion& start, const PinholeIntrinsics& K, const WeightedMatches& w, std::vector<uint8_t>& mask)
{
	Eigen::Matrix3d Km;
	Km << K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1;
	const Eigen::Matrix3d Kinv = Km.inverse();
	std::vector<int> all(w.size());
	std::iota(all.begin(), all.end(), 0);
	RelativeMotion m = start;
	// The mask was gated by the linear model and is biased towards it (pairs it fits badly are
	// missing): minimise, re-gate every pair at chi2(1) 95 % on the refined motion's Sampson
	// error (~N(0, 1)), and repeat until the set is stable (a few rounds).
	for (int round = 0; round < 4; round++)
	{
		std::vector<int> idx;
		for (std::size_t i = 0; i < w.size(); i++)
			if (mask[i]) idx.push_back(static_cast<int>(i));
		m = minimiseSampson(m, Kinv, w, idx);
		const Eigen::VectorXd r = sampson(m, Kinv, w, all);
		std::vector<uint8_t> next(w.size());
		for (std::size_t i = 0; i < w.size(); i++)
		{
			const double ri = r(static_cast<Eigen::Index>(i));
			next[i] = ri * ri <= kChi2OneDof ? 1 : 0;
		}
		if (next == mask) break;
		mask = std::move(next);
	}
	return m;
}

}  // namespace keygrid::sfm::detail
