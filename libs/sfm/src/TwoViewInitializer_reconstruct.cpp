// TwoViewInitializer, reconstruction: one motion hypothesis checked by triangulating the
// model's inliers (Mur-Artal et al. 2015, IV-D).
#include "TwoViewInitializerDetail.h"

#include <algorithm>
#include <cmath>

namespace keygrid::sfm::detail
{
namespace
{
constexpr double kDegToRad = M_PI / 180.0;

/** Squared reprojection error [px^2] of the camera-frame point X at pixel px. A point behind
 * the camera projects through its ray's mirror image; such points are only kept at parallax
 * too low for their depth sign to mean anything (see checkMotion). */
double reprojection2(const PinholeIntrinsics& K, const Eigen::Vector3d& X, const Eigen::Vector2d& px)
{
	const double u = K.fx * X.x() / X.z() + K.cx, v = K.fy * X.y() / X.z() + K.cy;
	return (Eigen::Vector2d(u, v) - px).squaredNorm();
}

Eigen::Vector3d ray(const PinholeIntrinsics& K, const Eigen::Vector2d& px)
{
	return {(px.x() - K.cx) / K.fx, (px.y() - K.cy) / K.fy, 1.0};
}
}  // namespace

/* For each inlier: triangulate (linear), then
 *  - parallax: the angle at X between the rays to the camera centres O_ref = 0 and
 *    O_cur = -R^T t; its cosine decides whether the depth sign is meaningful: near 0 parallax
 *    the DLT point can land on either side of the cameras (noise flips it), so cheirality is
 *    only enforced above minPointParallaxDeg, as ORB-SLAM does;
 *  - cheirality: z > 0 in both camera frames;
 *  - reprojection: e^2 / sigma^2 <= 5.99 (chi2, 2 dof) in each view at that view's sigma.
 * Points passing are "good"; good and above the per-point parallax they are valid map points.
 * The wrong hypotheses put most points behind a camera (or reproject them badly for the twisted
 * rotation), so the count of good points separates them. */
HypothesisCheck checkMotion(
	const RelativeMotion& m, const PinholeIntrinsics& K, const WeightedMatches& w, const std::vector<uint8_t>& inliers,
	const TwoViewOptions& opts)
{
	HypothesisCheck out;
	out.points_ref.assign(w.size(), Eigen::Vector3d::Zero());
	out.valid.assign(w.size(), 0);
	out.goodMask.assign(w.size(), 0);
	const double cosMinPoint = std::cos(opts.minPointParallaxDeg * kDegToRad);
	const Eigen::Vector3d O_cur = -m.R_cur_ref.transpose() * m.t_cur_ref;  // in the reference frame
	std::vector<double> parallax;
	parallax.reserve(w.size());
	for (std::size_t i = 0; i < w.size(); i++)
	{
		if (!inliers[i]) continue;
		const auto& pr = w.m->px_ref[i];
		const auto& pc = w.m->px_cur[i];
		Eigen::Vector3d X;
		if (!triangulateRays(ray(K, pr), ray(K, pc), m, X)) continue;
		const Eigen::Vector3d X_cur = m.R_cur_ref * X + m.t_cur_ref;
		const Eigen::Vector3d d_ref = X, d_cur = X - O_cur;
		const double cosPar = d_ref.dot(d_cur) / (d_ref.norm() * d_cur.norm());
		if (!std::isfinite(cosPar)) continue;
		const bool enoughParallax = cosPar < cosMinPoint;
		if (enoughParallax && (X.z() <= 0 || X_cur.z() <= 0)) continue;
		if (reprojection2(K, X, pr) * w.invVarRef[i] > kChi2TwoDof) continue;
		if (reprojection2(K, X_cur, pc) * w.invVarCur[i] > kChi2TwoDof) continue;
		out.good++;
		out.goodMask[i] = 1;
		parallax.push_back(std::acos(std::clamp(cosPar, -1.0, 1.0)) / kDegToRad);
		out.points_ref[i] = X;
		if (enoughParallax)
		{
			out.valid[i] = 1;
			out.numValid++;
		}
	}
	if (!parallax.empty())
	{
		const auto mid = parallax.begin() + static_cast<std::ptrdiff_t>(parallax.size() / 2);
		std::nth_element(parallax.begin(), mid, parallax.end());
		out.medianParallaxDeg = *mid;
	}
	return out;
}

}  // namespace keygrid::sfm::detail
