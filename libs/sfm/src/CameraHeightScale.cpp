// CameraHeightScaleEstimator: the floor among the map points below the keyframe cameras (the
// RGB-D floor frame's lowest-plane search), the cameras' height above it, s = camera_height / h.
#include <keygrid/maps/FloorFrameEstimator.h>
#include <keygrid/sfm/CameraHeightScale.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace keygrid::sfm
{
core::OptionFields CameraHeightScaleOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("camera_height", cameraHeight, "camera's optical centre above the floor [m]; 0 = unknown (map up to scale)", R::atLeast(0));
	f.add("min_keyframes", minKeyframes, "fewer keyframes are refused", R::atLeast(1));
	f.add("min_points_below", minPointsBelow, "fewer map points below the cameras are refused", R::atLeast(3));
	f.add("min_depression_deg", minDepressionDeg, "a point this far under its nearest camera's horizontal is below [deg]", R::fromBelow(0, 90));
	f.add("inlier_distance", inlierDistance, "point-to-plane distance of a floor inlier [m, map at the estimated scale]", R::positive());
	f.add("below_distance", belowDistance, "a point this far under a plane is below it [m, map at the estimated scale]", R::positive());
	f.add("max_below_share", maxBelowShare, "more points below a plane than this x the least floor support: not the floor", R::atLeast(0));
	f.add("max_tilt_deg", maxTiltDeg, "largest angle floor normal / cameras' mean -y [deg]", R::between(0, 90));
	f.add("hypotheses", hypotheses, "RANSAC plane hypotheses per search round", R::atLeast(1));
	f.add("min_floor_share", minFloorShare, "least floor support: share of the points below ...", R::aboveUpTo(0, 1));
	f.add("min_floor_points", minFloorPoints, "... and least number of points", R::atLeast(3));
	f.add("max_height_spread", maxHeightSpread, "refused above this robust relative spread of the keyframes' heights", R::positive());
	f.add("seed", seed, "RANSAC seed (reproducible estimates)");
	return f;
}

void CameraHeightScaleOptions::validate(const std::string& section) const { core::validateFields(*this, section); }

const char* toString(CameraHeightScaleFailure f)
{
	switch (f)
	{
		case CameraHeightScaleFailure::None: return "none";
		case CameraHeightScaleFailure::TooFewKeyframes: return "too few keyframes";
		case CameraHeightScaleFailure::TooFewPointsBelow: return "too few map points below the cameras";
		case CameraHeightScaleFailure::NoFloorPlane: return "no floor plane";
		case CameraHeightScaleFailure::FloorNotClear: return "floor not seen (points under every large plane)";
		case CameraHeightScaleFailure::HeightSpread: return "cameras not at one height";
		case CameraHeightScaleFailure::NotConverged: return "scale not converged";
	}
	return "?";
}

CameraHeightScaleEstimator::CameraHeightScaleEstimator(const CameraHeightScaleOptions& opts) : m_opts(opts)
{
	m_opts.validate();
	if (!(m_opts.cameraHeight > 0))
		throw std::invalid_argument(
			"[camera_height_scale] camera_height = " + std::to_string(m_opts.cameraHeight) + " (must be > 0 for a metric scale)");
}

namespace
{
/** Plane searches at most. */
constexpr int kMaxPasses = 4;
/** The scale has settled when a search's result is within this share of the scale its
 * tolerances were set with: a fraction of the inlier band small next to the differences
 * between successive searches on a noisy map, which the points that noise moves in or out of
 * the band cause. */
constexpr double kSettled = 0.01;
/** First estimate of h_map: this quantile of the points' depth below their nearest camera. The
 * floor is the lowest surface, so the upper tail of that depth is the camera height; a high
 * quantile errs towards a larger h_map, whose looser tolerances are the safer side (tighter
 * ones count the floor's own noise as points under it). */
constexpr double kFirstHeightQuantile = 0.95;
/** A floor candidate must keep (all but 5 % of) the cameras this share of camera_height above
 * it: loose, as it holds at the first, rough scale too; it only keeps planes next to the
 * cameras out. */
constexpr double kMinCameraHeightShare = 0.25;
/** 1.4826 MAD estimates the std of a normal distribution. */
constexpr double kMadToStd = 1.4826;

CameraHeightScaleResult fail(CameraHeightScaleResult r, CameraHeightScaleFailure f, const std::string& why)
{
	r.ok = false;
	r.failure = f;
	r.message = std::string(toString(f)) + ": " + why;
	return r;
}

double median(std::vector<double> v)
{
	const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
	std::nth_element(v.begin(), mid, v.end());
	if (v.size() % 2 == 1) return *mid;
	return 0.5 * (*mid + *std::max_element(v.begin(), mid));
}

double quantile(std::vector<double> v, double q)
{
	const auto k = static_cast<std::ptrdiff_t>(std::floor(q * static_cast<double>(v.size() - 1)));
	std::nth_element(v.begin(), v.begin() + k, v.end());
	return v[static_cast<std::size_t>(k)];
}

bool finite(const Eigen::Vector3d& v) { return v.allFinite(); }

/** The points below the cameras and their depth below their nearest camera along `up`. */
struct BelowPoints
{
	std::vector<std::size_t> index;
	std::vector<double> depth;  //!< up . (c_nearest - p) [map units]
};

/** Point i is below when up . (c - p) >= sin(minDepression) |c - p| with c its nearest camera:
 * the camera sees it at least minDepression under its horizontal. */
BelowPoints selectBelow(
	const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& centres,
	const std::vector<std::size_t>& nearest, const Eigen::Vector3d& up, double minDepressionDeg)
{
	const double sinMin = std::sin(minDepressionDeg * M_PI / 180.0);
	BelowPoints b;
	for (std::size_t i = 0; i < points.size(); i++)
	{
		const Eigen::Vector3d d = centres[nearest[i]] - points[i];
		const double depth = up.dot(d);
		if (depth > 0 && depth >= sinMin * d.norm())
		{
			b.index.push_back(i);
			b.depth.push_back(depth);
		}
	}
	return b;
}

mrpt::math::TPoint3D toTPoint(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }
}  // namespace

CameraHeightScaleResult CameraHeightScaleEstimator::estimate(
	const std::vector<mrpt::poses::CPose3D>& T_world_cam, const std::vector<Eigen::Vector3d>& points_world) const
{
	const CameraHeightScaleOptions& o = m_opts;
	CameraHeightScaleResult r;
	const std::size_t nKf = T_world_cam.size();
	if (nKf < static_cast<std::size_t>(o.minKeyframes))
		return fail(r, CameraHeightScaleFailure::TooFewKeyframes, std::to_string(nKf) + " < min_keyframes = " + std::to_string(o.minKeyframes));

	// Camera centres and "up" = mean of the cameras' -y axes (optical frame, y down).
	std::vector<Eigen::Vector3d> centres(nKf);
	Eigen::Vector3d centroid = Eigen::Vector3d::Zero(), up = Eigen::Vector3d::Zero();
	for (std::size_t k = 0; k < nKf; k++)
	{
		const auto& T = T_world_cam[k];
		centres[k] = Eigen::Vector3d(T.x(), T.y(), T.z());
		const auto R = T.getRotationMatrix();
		const Eigen::Vector3d down(R(0, 1), R(1, 1), R(2, 1));
		if (!finite(centres[k]) || !finite(down))
			throw std::invalid_argument("CameraHeightScaleEstimator: keyframe pose " + std::to_string(k) + " is not finite");
		centroid += centres[k];
		up -= down;
	}
	centroid /= static_cast<double>(nKf);
	if (!(up.norm() > 1e-6 * static_cast<double>(nKf)))
		return fail(r, CameraHeightScaleFailure::NoFloorPlane, "the cameras' down directions cancel out: no common \"up\"");
	up.normalize();

	// Nearest keyframe camera of each point (brute force: keyframes are few).
	std::vector<std::size_t> nearest(points_world.size());
	for (std::size_t i = 0; i < points_world.size(); i++)
	{
		if (!finite(points_world[i]))
			throw std::invalid_argument("CameraHeightScaleEstimator: point " + std::to_string(i) + " is not finite");
		double best = std::numeric_limits<double>::infinity();
		for (std::size_t k = 0; k < nKf; k++)
		{
			const double d2 = (points_world[i] - centres[k]).squaredNorm();
			if (d2 < best) best = d2, nearest[i] = k;
		}
	}

	maps::FloorFrameOptions search;
	search.inlierDistance = o.inlierDistance;
	search.belowDistance = o.belowDistance;
	search.maxBelowShare = o.maxBelowShare;
	search.searchUnderTheWinner = true;
	search.maxTiltDeg = o.maxTiltDeg;
	search.hypotheses = o.hypotheses;
	search.minSupport = o.minFloorShare;
	search.minSupportPoints = o.minFloorPoints;
	search.minCameraHeight = kMinCameraHeightShare * o.cameraHeight;
	search.seed = o.seed;

	// The search runs on sigma (x - centroid): the map in approximately metres, where its
	// metric tolerances mean what they say. sigma = the previous pass's scale.
	double sigma = 0;
	bool settled = false;
	std::vector<mrpt::math::TPoint3D> cams_n(nKf);
	for (int pass = 1; pass <= kMaxPasses && !settled; pass++)
	{
		r.passes = pass;
		const BelowPoints below = selectBelow(points_world, centres, nearest, up, o.minDepressionDeg);
		r.pointsBelow = below.index.size();
		if (r.pointsBelow < static_cast<std::size_t>(o.minPointsBelow))
			return fail(
				r, CameraHeightScaleFailure::TooFewPointsBelow,
				std::to_string(r.pointsBelow) + " of " + std::to_string(points_world.size()) + " points < min_points_below = " +
					std::to_string(o.minPointsBelow));
		if (pass == 1)
		{
			const double h0 = quantile(below.depth, kFirstHeightQuantile);
			sigma = o.cameraHeight / h0;
		}
		std::vector<mrpt::math::TPoint3D> pts_n(below.index.size());
		for (std::size_t j = 0; j < below.index.size(); j++) pts_n[j] = toTPoint(sigma * (points_world[below.index[j]] - centroid));
		for (std::size_t k = 0; k < nKf; k++) cams_n[k] = toTPoint(sigma * (centres[k] - centroid));

		const auto fit = maps::estimateLowestFloorPlane(pts_n, mrpt::math::TVector3D(up.x(), up.y(), up.z()), cams_n, search);
		if (!fit)
		{
			std::ostringstream why;
			why << "no plane within " << o.maxTiltDeg << " deg of \"up\" holds " << o.minFloorPoints << " and " << o.minFloorShare * 100
				<< " % of the " << r.pointsBelow << " points below the cameras with the cameras above it";
			return fail(r, CameraHeightScaleFailure::NoFloorPlane, why.str());
		}
		// n . sigma (p - centroid) + d_n = 0  <=>  n . p + (d_n / sigma - n . centroid) = 0.
		const auto& pl = fit->plane;
		r.floorNormal = Eigen::Vector3d(pl.normal.x, pl.normal.y, pl.normal.z);
		r.floorOffset = pl.d / sigma - r.floorNormal.dot(centroid);
		r.floorInliers = pl.inliers;
		r.pointsUnderFloor = fit->below;
		r.parallelPlanes = fit->parallelPlanes;
		r.verticalPlanes = fit->verticalPlanes;
		r.keyframeHeights.resize(nKf);
		for (std::size_t k = 0; k < nKf; k++) r.keyframeHeights[k] = r.floorNormal.dot(centres[k]) + r.floorOffset;
		r.heightMap = median(r.keyframeHeights);
		if (!fit->clearBelow)
			return fail(
				r, CameraHeightScaleFailure::FloorNotClear,
				"the lowest large plane has " + std::to_string(fit->below) + " of the " + std::to_string(r.pointsBelow) + " points under it");
		if (!(r.heightMap > 0))
			return fail(r, CameraHeightScaleFailure::NoFloorPlane, "the median keyframe is not above the plane found");
		const double scale = o.cameraHeight / r.heightMap;
		settled = std::abs(scale / sigma - 1) < kSettled;
		sigma = scale;
		up = r.floorNormal;
	}
	r.scale = sigma;

	std::vector<double> dev(nKf);
	for (std::size_t k = 0; k < nKf; k++) dev[k] = std::abs(r.keyframeHeights[k] - r.heightMap);
	r.heightSpread = kMadToStd * median(dev) / r.heightMap;
	std::ostringstream msg;
	msg << "h_map = " << r.heightMap << " map units (spread " << 100 * r.heightSpread << " %), s = " << r.scale << " m per unit, floor "
		<< r.floorInliers << " of " << r.pointsBelow << " points below the cameras, " << r.passes << " passes";
	if (!settled) return fail(r, CameraHeightScaleFailure::NotConverged, msg.str());
	if (r.heightSpread > o.maxHeightSpread)
	{
		std::ostringstream why;
		why << "robust spread of the " << nKf << " keyframes' heights " << 100 * r.heightSpread << " % > max_height_spread = " << 100 * o.maxHeightSpread
			<< " %; " << msg.str();
		return fail(r, CameraHeightScaleFailure::HeightSpread, why.str());
	}
	r.ok = true;
	r.message = msg.str();
	return r;
}

void rescaleMap(double s, std::vector<mrpt::poses::CPose3D>& T_world_cam, std::vector<Eigen::Vector3d>& points_world)
{
	for (auto& T : T_world_cam)
	{
		T.x(s * T.x());
		T.y(s * T.y());
		T.z(s * T.z());
	}
	for (auto& p : points_world) p *= s;
}

}  // namespace keygrid::sfm
