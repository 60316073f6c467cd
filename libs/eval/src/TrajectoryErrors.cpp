#include <keygrid/core/JsonNumber.h>
#include <keygrid/core/TimestampAssociation.h>
#include <keygrid/eval/TrajectoryErrors.h>
#include <mrpt/core/bits_math.h>

#include <Eigen/LU>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace keygrid::eval
{
bool TrajectoryErrorOptions::isValid(std::string* error) const
{
	std::string e;
	if (!(maxDt > 0 && std::isfinite(maxDt))) e = "maxDt must be > 0, got " + std::to_string(maxDt);
	else if (!(rpeDelta > 0 && std::isfinite(rpeDelta)))
		e = "rpeDelta must be > 0, got " + std::to_string(rpeDelta);
	if (error) *error = e;
	return e.empty();
}

ErrorStats ErrorStats::Of(std::vector<double> v)
{
	ErrorStats s;
	s.count = v.size();
	if (v.empty()) return s;
	double sum = 0, sq = 0;
	for (double e : v)
	{
		sum += e;
		sq += e * e;
	}
	const double n = static_cast<double>(v.size());
	s.mean = sum / n;
	s.rmse = std::sqrt(sq / n);
	s.stddev = std::sqrt(std::max(0.0, sq / n - s.mean * s.mean));
	std::sort(v.begin(), v.end());
	s.min = v.front();
	s.max = v.back();
	s.median = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
	return s;
}

Similarity3 alignTrajectoryPoses(const core::Trajectory& gt, const core::Trajectory& est, double maxDt)
{
	std::vector<double> te, tg;
	for (const auto& p : est) te.push_back(p.t);
	for (const auto& p : gt) tg.push_back(p.t);
	std::vector<mrpt::poses::CPose3D> x, y;
	for (const auto& [i, j] : core::associateTimestamps(te, tg, maxDt))
	{
		x.push_back(est[i].T_world_cam);
		y.push_back(gt[j].T_world_cam);
	}
	if (x.size() < 3)
		throw std::invalid_argument("alignTrajectoryPoses: only " + std::to_string(x.size()) + " estimated poses have a ground-truth pose within " +
									std::to_string(maxDt) + " s (need >= 3)");
	return alignPoses(x, y);
}

TrajectoryErrors evaluateTrajectory(
	const core::Trajectory& gt, const core::Trajectory& est, const TrajectoryErrorOptions& opts)
{
	std::string why;
	if (!opts.isValid(&why)) throw std::invalid_argument("evaluateTrajectory: " + why);
	TrajectoryErrors out;
	out.gtPoses = gt.size();
	out.estPoses = est.size();
	out.rpeDelta = opts.rpeDelta;

	std::vector<double> te, tg;
	for (const auto& p : est) te.push_back(p.t);
	for (const auto& p : gt) tg.push_back(p.t);
	const auto matches = core::associateTimestamps(te, tg, opts.maxDt);
	out.matched = matches.size();
	if (matches.size() < 3)
		throw std::invalid_argument(
			"only " + std::to_string(matches.size()) + " estimated poses have a ground-truth pose within " +
			std::to_string(opts.maxDt) + " s (need >= 3); do the timestamps match?");

	// --- ATE: align estimated positions onto ground truth, then the residual positions.
	std::vector<Eigen::Vector3d> x, y;
	for (const auto& [i, j] : matches)
	{
		const auto& pe = est[i].T_world_cam;
		const auto& pg = gt[j].T_world_cam;
		x.emplace_back(pe.x(), pe.y(), pe.z());
		y.emplace_back(pg.x(), pg.y(), pg.z());
	}
	out.alignment = opts.fixedAlignment ? *opts.fixedAlignment : alignPointSets(x, y, opts.withScale);
	std::vector<double> ate;
	for (std::size_t k = 0; k < x.size(); k++) ate.push_back((out.alignment.apply(x[k]) - y[k]).norm());
	out.ate = ErrorStats::Of(ate);

	// --- Orientation: R_a = argmin sum_k |R_gt_k - R_a R_est_k|_F^2 (chordalMeanRotation), then
	// the angle of each residual rotation.
	{
		std::vector<Eigen::Matrix3d> Rest, Rgt;
		for (const auto& [i, j] : matches)
		{
			Rest.push_back(est[i].T_world_cam.getRotationMatrix().asEigen());
			Rgt.push_back(gt[j].T_world_cam.getRotationMatrix().asEigen());
		}
		const Eigen::Matrix3d Ra = opts.fixedAlignment ? opts.fixedAlignment->R : chordalMeanRotation(Rest, Rgt);
		std::vector<double> angles;
		for (std::size_t k = 0; k < Rest.size(); k++)
		{
			const Eigen::Matrix3d E = Rgt[k].transpose() * Ra * Rest[k];
			angles.push_back(mrpt::RAD2DEG(std::acos(std::clamp((E.trace() - 1.0) / 2.0, -1.0, 1.0))));
		}
		out.ateRotDeg = ErrorStats::Of(angles);
	}

	// --- RPE: for each matched pose i, the matched pose j closest to t_i + delta;
	// E = inv(inv(G_i) G_j) * inv(E_i) E_j, errors |trans(E)| and angle(E) per delta seconds.
	std::vector<double> rt, rr;
	// The partner must sit within the association tolerance of t_i + delta (no short pairs at
	// the end of the sequence).
	const double tol = opts.maxDt;
	for (std::size_t a = 0; a < matches.size(); a++)
	{
		const double target = est[matches[a].first].t + opts.rpeDelta;
		std::size_t best = a;
		double bestDt = 1e300;
		// matches are sorted by time: scan forward from a
		for (std::size_t b = a + 1; b < matches.size(); b++)
		{
			const double dt = std::abs(est[matches[b].first].t - target);
			if (dt < bestDt)
			{
				bestDt = dt;
				best = b;
			}
			else if (est[matches[b].first].t > target)
				break;
		}
		if (best == a || bestDt > tol) continue;
		const auto& Ei = est[matches[a].first].T_world_cam;
		const auto& Ej = est[matches[best].first].T_world_cam;
		const auto& Gi = gt[matches[a].second].T_world_cam;
		const auto& Gj = gt[matches[best].second].T_world_cam;
		const mrpt::poses::CPose3D relEst = Ej - Ei;  // inv(Ei) * Ej
		const mrpt::poses::CPose3D relGt = Gj - Gi;
		const mrpt::poses::CPose3D E = relEst - relGt;  // inv(relGt) * relEst
		rt.push_back(E.translation().norm() / opts.rpeDelta);
		const auto R = E.getRotationMatrix();
		const double c = std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0);
		rr.push_back(mrpt::RAD2DEG(std::acos(c)) / opts.rpeDelta);
	}
	if (!rt.empty())
	{
		out.rpeTrans = ErrorStats::Of(rt);
		out.rpeRotDeg = ErrorStats::Of(rr);
	}
	return out;
}

std::string TrajectoryErrors::toJson() const
{
	std::ostringstream o;
	o << "{\n";
	o << "  \"ate_rmse_m\": " << core::jsonNumber(ate.rmse) << ",\n";
	o << "  \"ate_mean_m\": " << core::jsonNumber(ate.mean) << ",\n";
	o << "  \"ate_median_m\": " << core::jsonNumber(ate.median) << ",\n";
	o << "  \"ate_std_m\": " << core::jsonNumber(ate.stddev) << ",\n";
	o << "  \"ate_min_m\": " << core::jsonNumber(ate.min) << ",\n";
	o << "  \"ate_max_m\": " << core::jsonNumber(ate.max) << ",\n";
	o << "  \"ate_rot_rmse_deg\": " << core::jsonNumber(ateRotDeg.rmse) << ",\n";
	o << "  \"rpe_trans_m_per_s\": " << (rpeTrans ? core::jsonNumber(rpeTrans->rmse) : "null") << ",\n";
	o << "  \"rpe_rot_deg_per_s\": " << (rpeRotDeg ? core::jsonNumber(rpeRotDeg->rmse) : "null") << ",\n";
	o << "  \"rpe_pairs\": " << (rpeTrans ? rpeTrans->count : 0) << ",\n";
	o << "  \"rpe_delta_s\": " << core::jsonNumber(rpeDelta) << ",\n";
	o << "  \"matched\": " << matched << ",\n";
	o << "  \"gt_poses\": " << gtPoses << ",\n";
	o << "  \"est_poses\": " << estPoses << ",\n";
	o << "  \"alignment_scale\": " << core::jsonNumber(alignment.s) << "\n";
	o << "}\n";
	return o.str();
}

std::string TrajectoryErrors::toText() const
{
	char b[512];
	std::ostringstream o;
	std::snprintf(
		b, sizeof(b), "matched %zu of %zu estimated poses (%zu ground-truth poses)\n", matched,
		estPoses, gtPoses);
	o << b;
	std::snprintf(
		b, sizeof(b), "ATE rmse %.6f m  mean %.6f  median %.6f  max %.6f\n", ate.rmse, ate.mean,
		ate.median, ate.max);
	o << b;
	if (rpeTrans)
	{
		std::snprintf(
			b, sizeof(b), "RPE rmse %.6f m/s  %.6f deg/s  (%zu pairs, delta %.3g s)\n", rpeTrans->rmse,
			rpeRotDeg->rmse, rpeTrans->count, rpeDelta);
		o << b;
	}
	else
	{
		std::snprintf(b, sizeof(b), "RPE n/a: matched poses span less than delta = %.3g s\n", rpeDelta);
		o << b;
	}
	if (alignment.s != 1.0)
	{
		std::snprintf(b, sizeof(b), "Sim(3) alignment scale %.6f\n", alignment.s);
		o << b;
	}
	return o.str();
}

}  // namespace keygrid::eval
