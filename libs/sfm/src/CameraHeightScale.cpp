// CameraHeightScaleEstimator: the floor among the map points below the keyframe cameras (the
// RGB-D floor frame's lowest-plane search), the cameras' height above it, s = camera_height / h.
#include <keygrid/core/VectorAngle.h>
#include <keygrid/maps/FloorFrameEstimator.h>
#include <keygrid/sfm/CameraHeightScale.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

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
	f.add("level_min_turn_deg", levelMinTurnDeg, "once the keyframes turned this much, a floor off their turn axis is refused [deg]; 0 = never", R::inRange(0, 360));
	f.add("level_max_tilt_deg", levelMaxTiltDeg, "largest angle floor normal / the keyframes' turn axis [deg]", R::between(0, 90));
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
		case CameraHeightScaleFailure::OffTurnAxis: return "floor off the keyframes' turn axis";
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

double angleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return core::angleBetween(a, b) * 180.0 / M_PI; }

/** The axis the cameras turned about, for cameras without roll: their x axes lie in the
 * floor's directions, so the floor's normal is the unit a minimizing sum_k (a . x_k)^2, the
 * eigenvector of the smallest eigenvalue of sum_k x_k x_k^T, signed towards `up`. The turn is
 * the range of the x axes' angles about it, measured from the direction most along them
 * (the largest eigenvalue's eigenvector). */
struct TurnAxis
{
	Eigen::Vector3d axis{Eigen::Vector3d::Zero()};
	double turnDeg{0};
};

TurnAxis turnAxisOf(const std::vector<Eigen::Vector3d>& xAxes, const Eigen::Vector3d& up)
{
	TurnAxis t;
	if (xAxes.size() < 2) return t;
	Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
	for (const auto& x : xAxes) m += x * x.transpose();
	const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(m);  // eigenvalues ascending
	t.axis = eig.eigenvectors().col(0).normalized();
	if (t.axis.dot(up) < 0) t.axis = -t.axis;
	// The turn is the arc the x axes' headings about the axis cover: the full circle less the
	// largest gap between neighbouring headings (the eigenvectors' signs are arbitrary, so the
	// headings may straddle +-pi however little the cameras turned).
	const Eigen::Vector3d ref = eig.eigenvectors().col(2), side = t.axis.cross(ref);
	std::vector<double> heading;
	heading.reserve(xAxes.size());
	for (const auto& x : xAxes) heading.push_back(std::atan2(x.dot(side), x.dot(ref)));
	std::sort(heading.begin(), heading.end());
	double largestGap = heading.front() + 2 * M_PI - heading.back();
	for (std::size_t k = 1; k < heading.size(); k++) largestGap = std::max(largestGap, heading[k] - heading[k - 1]);
	t.turnDeg = (2 * M_PI - largestGap) * 180.0 / M_PI;
	return t;
}

/** What every plane search of one estimate shares. */
struct SearchInput
{
	const std::vector<Eigen::Vector3d>& points;
	std::vector<Eigen::Vector3d> centres;
	std::vector<std::size_t> nearest;  //!< nearest keyframe camera of each point
	Eigen::Vector3d centroid{Eigen::Vector3d::Zero()};
	TurnAxis turn;
};

/** The passes of the plane search (header): the floor among the points below the cameras
 * along `up`, first with the hint `up` and maxTiltDeg; with aroundTurnAxis every pass's hint
 * is the turn axis and the tolerance levelMaxTiltDeg, otherwise the previous pass's floor. */
CameraHeightScaleResult searchFloor(const CameraHeightScaleOptions& o, const SearchInput& in, Eigen::Vector3d up, bool aroundTurnAxis)
{
	CameraHeightScaleResult r;
	r.turnDeg = in.turn.turnDeg;
	r.turnAxis = in.turn.axis;
	r.searchedAroundTurnAxis = aroundTurnAxis;
	const std::size_t nKf = in.centres.size();
	const double tiltDeg = aroundTurnAxis ? o.levelMaxTiltDeg : o.maxTiltDeg;
	maps::FloorFrameOptions search;
	search.inlierDistance = o.inlierDistance;
	search.belowDistance = o.belowDistance;
	search.maxBelowShare = o.maxBelowShare;
	search.searchUnderTheWinner = true;
	search.maxTiltDeg = tiltDeg;
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
		const BelowPoints below = selectBelow(in.points, in.centres, in.nearest, up, o.minDepressionDeg);
		r.pointsBelow = below.index.size();
		if (r.pointsBelow < static_cast<std::size_t>(o.minPointsBelow))
			return fail(
				r, CameraHeightScaleFailure::TooFewPointsBelow,
				std::to_string(r.pointsBelow) + " of " + std::to_string(in.points.size()) + " points < min_points_below = " +
					std::to_string(o.minPointsBelow));
		if (pass == 1)
		{
			const double h0 = quantile(below.depth, kFirstHeightQuantile);
			sigma = o.cameraHeight / h0;
		}
		std::vector<mrpt::math::TPoint3D> pts_n(below.index.size());
		for (std::size_t j = 0; j < below.index.size(); j++) pts_n[j] = toTPoint(sigma * (in.points[below.index[j]] - in.centroid));
		for (std::size_t k = 0; k < nKf; k++) cams_n[k] = toTPoint(sigma * (in.centres[k] - in.centroid));

		const Eigen::Vector3d& hint = aroundTurnAxis ? in.turn.axis : up;
		const auto fit = maps::estimateLowestFloorPlane(pts_n, mrpt::math::TVector3D(hint.x(), hint.y(), hint.z()), cams_n, search);
		if (!fit)
		{
			std::ostringstream why;
			why << "no plane within " << tiltDeg << " deg of " << (aroundTurnAxis ? "the keyframes' turn axis" : "\"up\"") << " holds "
				<< o.minFloorPoints << " and " << o.minFloorShare * 100 << " % of the " << r.pointsBelow
				<< " points below the cameras with the cameras above it";
			return fail(r, CameraHeightScaleFailure::NoFloorPlane, why.str());
		}
		// n . sigma (p - centroid) + d_n = 0  <=>  n . p + (d_n / sigma - n . centroid) = 0.
		const auto& pl = fit->plane;
		r.floorNormal = Eigen::Vector3d(pl.normal.x, pl.normal.y, pl.normal.z);
		r.floorOffset = pl.d / sigma - r.floorNormal.dot(in.centroid);
		r.floorToTurnAxisDeg = in.turn.turnDeg > 0 ? angleDeg(r.floorNormal, in.turn.axis) : 0.0;
		r.floorInliers = pl.inliers;
		r.pointsUnderFloor = fit->below;
		r.parallelPlanes = fit->parallelPlanes;
		r.verticalPlanes = fit->verticalPlanes;
		r.keyframeHeights.resize(nKf);
		for (std::size_t k = 0; k < nKf; k++) r.keyframeHeights[k] = r.floorNormal.dot(in.centres[k]) + r.floorOffset;
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
		<< r.floorInliers << " of " << r.pointsBelow << " points below the cameras, " << r.passes << " passes, floor " << r.floorToTurnAxisDeg
		<< " deg off the turn axis (turned " << r.turnDeg << " deg)";
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
}  // namespace

CameraHeightScaleResult CameraHeightScaleEstimator::estimate(
	const std::vector<mrpt::poses::CPose3D>& T_world_cam, const std::vector<Eigen::Vector3d>& points_world) const
{
	const CameraHeightScaleOptions& o = m_opts;
	CameraHeightScaleResult r;
	const std::size_t nKf = T_world_cam.size();
	if (nKf < static_cast<std::size_t>(o.minKeyframes))
		return fail(r, CameraHeightScaleFailure::TooFewKeyframes, std::to_string(nKf) + " < min_keyframes = " + std::to_string(o.minKeyframes));

	// Camera centres, x axes and "up" = mean of the cameras' -y axes (optical frame, y down).
	SearchInput in{points_world, std::vector<Eigen::Vector3d>(nKf), std::vector<std::size_t>(points_world.size()), Eigen::Vector3d::Zero(), {}};
	std::vector<Eigen::Vector3d> xAxes(nKf);
	Eigen::Vector3d up = Eigen::Vector3d::Zero();
	for (std::size_t k = 0; k < nKf; k++)
	{
		const auto& T = T_world_cam[k];
		in.centres[k] = Eigen::Vector3d(T.x(), T.y(), T.z());
		const auto R = T.getRotationMatrix();
		const Eigen::Vector3d down(R(0, 1), R(1, 1), R(2, 1));
		xAxes[k] = Eigen::Vector3d(R(0, 0), R(1, 0), R(2, 0));
		if (!finite(in.centres[k]) || !finite(down) || !finite(xAxes[k]))
			throw std::invalid_argument("CameraHeightScaleEstimator: keyframe pose " + std::to_string(k) + " is not finite");
		in.centroid += in.centres[k];
		up -= down;
	}
	in.centroid /= static_cast<double>(nKf);
	if (!(up.norm() > 1e-6 * static_cast<double>(nKf)))
		return fail(r, CameraHeightScaleFailure::NoFloorPlane, "the cameras' down directions cancel out: no common \"up\"");
	up.normalize();
	in.turn = turnAxisOf(xAxes, up);

	// Nearest keyframe camera of each point (brute force: keyframes are few).
	for (std::size_t i = 0; i < points_world.size(); i++)
	{
		if (!finite(points_world[i]))
			throw std::invalid_argument("CameraHeightScaleEstimator: point " + std::to_string(i) + " is not finite");
		double best = std::numeric_limits<double>::infinity();
		for (std::size_t k = 0; k < nKf; k++)
		{
			const double d2 = (points_world[i] - in.centres[k]).squaredNorm();
			if (d2 < best) best = d2, in.nearest[i] = k;
		}
	}

	r = searchFloor(o, in, up, false);
	// Cameras that turned enough: a floor found further than levelMaxTiltDeg off their turn
	// axis is not the floor they move on (header) and is searched for again around that axis.
	// A search that failed stays failed: only what would have been taken is checked.
	const bool turned = o.levelMinTurnDeg > 0 && in.turn.turnDeg >= o.levelMinTurnDeg && angleDeg(in.turn.axis, up) <= o.maxTiltDeg;
	if (turned && r.ok && r.floorToTurnAxisDeg > o.levelMaxTiltDeg)
	{
		std::ostringstream first;
		first << "a plane " << r.floorToTurnAxisDeg << " deg off the keyframes' turn axis (turned " << in.turn.turnDeg
			  << " deg; it gave s = " << r.scale << " m per unit) was not the floor; searched around the axis: ";
		r = searchFloor(o, in, in.turn.axis, true);
		if (r.ok && r.floorToTurnAxisDeg > o.levelMaxTiltDeg)
		{
			std::ostringstream why;
			why << r.floorToTurnAxisDeg << " deg > level_max_tilt_deg = " << o.levelMaxTiltDeg << " after its refinement; " << r.message;
			r = fail(r, CameraHeightScaleFailure::OffTurnAxis, why.str());
		}
		r.message = first.str() + r.message;
	}
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
