// TwoViewInitializer: options, model selection and the choice among motion hypotheses
// (Mur-Artal et al. 2015, section IV). Model fits: _models.cpp; hypothesis checks:
// _reconstruct.cpp.
#include <keygrid/sfm/TwoViewInitializer.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <future>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "TwoViewInitializerDetail.h"

namespace keygrid::sfm
{
core::OptionFields TwoViewOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("ransac_iterations", ransacIterations, "RANSAC draws shared by H and F", R::inRange(1, 100000));
	f.add("seed", seed, "RNG seed (reproducible runs)");
	f.add("sigma_px", sigmaPx, "keypoint std at level 0 [px]", R::positive());
	f.add("min_matches", minMatches, "fewer correspondences are refused (the 8-point needs 8)", R::inRange(8, 1000000));
	f.add("min_parallax_deg", minParallaxDeg, "median parallax needed [deg]", R::fromBelow(0, 90));
	f.add("min_point_parallax_deg", minPointParallaxDeg, "a map point needs this parallax [deg]", R::fromBelow(0, 90));
	f.add("min_triangulated", minTriangulated, "map points needed", R::inRange(1, 1000000));
	f.add("min_good_share", minGoodShare, "share of inliers the chosen motion must explain", R::inRange(0, 1));
	f.add("max_second_best_share", maxSecondBestShare, "second-best / best good points above: ambiguous", R::aboveUpTo(0, 1));
	f.add("rival_parallax_share", rivalParallaxShare, "a competing motion below min_parallax_deg and this share of the best's parallax is no rival; 0 = off", R::inRange(0, 1));
	f.add("rival_max_rotation_ratio", rivalMaxRotationRatio, "... when the best motion's rotation is at most this many times its parallax", R::positive());
	f.add("homography_ratio", homographyRatio, "R_H = S_H / (S_H + S_F) above: homography", R::between(0, 1));
	f.add("homography_inlier_share", homographyInlierShare, "H inliers / F inliers from which F is degenerate", R::aboveUpTo(0, 1));
	f.add("parallel", parallel, "score H and F in parallel");
	return f;
}

void TwoViewOptions::validate(const std::string& section) const { core::validateFields(*this, section); }

bool TwoViewOptions::isValid(std::string* error) const
{
	try
	{
		validate();
	}
	catch (const std::invalid_argument& e)
	{
		if (error) *error = e.what();
		return false;
	}
	if (error) error->clear();
	return true;
}

const char* toString(TwoViewFailure f)
{
	switch (f)
	{
		case TwoViewFailure::None: return "none";
		case TwoViewFailure::TooFewMatches: return "too few matches";
		case TwoViewFailure::LowParallax: return "low parallax (pure rotation?)";
		case TwoViewFailure::Ambiguous: return "ambiguous motion";
		case TwoViewFailure::TooFewTriangulated: return "too few triangulated points";
	}
	return "?";
}

const char* toString(TwoViewModel m)
{
	switch (m)
	{
		case TwoViewModel::None: return "none";
		case TwoViewModel::Homography: return "homography";
		case TwoViewModel::Fundamental: return "fundamental";
	}
	return "?";
}

TwoViewInitializer::TwoViewInitializer(const PinholeIntrinsics& K, const TwoViewOptions& opts) : m_K(K), m_opts(opts)
{
	opts.validate();
	if (!(K.fx > 0 && K.fy > 0)) throw std::invalid_argument("TwoViewInitializer: focal lengths must be > 0");
}

namespace
{
TwoViewResult fail(TwoViewResult r, TwoViewFailure f, const std::string& why)
{
	r.ok = false;
	r.failure = f;
	r.message = std::string(toString(f)) + ": " + why;
	return r;
}

detail::WeightedMatches weigh(const TwoViewMatches& m, double sigmaPx)
{
	const std::size_t n = m.px_ref.size();
	if (m.px_cur.size() != n || (!m.scale_ref.empty() && m.scale_ref.size() != n) || (!m.scale_cur.empty() && m.scale_cur.size() != n))
		throw std::invalid_argument("TwoViewMatches: px_ref, px_cur and non-empty scale_ref/scale_cur must have one entry per correspondence");
	detail::WeightedMatches w;
	w.m = &m;
	w.invVarRef.resize(n);
	w.invVarCur.resize(n);
	w.invVarPair.resize(n);
	for (std::size_t i = 0; i < n; i++)
	{
		const double sr = sigmaPx * (m.scale_ref.empty() ? 1.0 : m.scale_ref[i]);
		const double sc = sigmaPx * (m.scale_cur.empty() ? 1.0 : m.scale_cur[i]);
		if (!(sr > 0 && sc > 0)) throw std::invalid_argument("TwoViewMatches: scales must be > 0");
		w.invVarRef[i] = 1.0 / (sr * sr);
		w.invVarCur[i] = 1.0 / (sc * sc);
		w.invVarPair[i] = 1.0 / (sr * sr + sc * sc);
	}
	return w;
}

/** The motion hypotheses of the selected model; empty with a failure reason when it has none. */
std::vector<RelativeMotion> hypotheses(const TwoViewResult& r, const PinholeIntrinsics& K, TwoViewFailure& why, std::string& text)
{
	Eigen::Matrix3d Km;
	Km << K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1;
	if (r.model == TwoViewModel::Fundamental) return decomposeEssential(Km.transpose() * r.F_cur_ref * Km);
	const Eigen::Matrix3d A = Km.inverse() * r.H_cur_ref * Km;
	auto hs = decomposeHomography(A);
	if (hs.empty())
	{
		// A = lambda (R + t n^T / d): equal singular values mean t n^T / d ~ 0 (rotation only)
		// when all three coincide, a motion along the plane normal when two do.
		const Eigen::Vector3d sv = A.jacobiSvd().singularValues();
		const bool rotation = sv(0) / sv(2) < 1.0 + 1e-4;
		why = rotation ? TwoViewFailure::LowParallax : TwoViewFailure::Ambiguous;
		text = rotation ? "the homography is a rotation (no translation)" : "homography decomposition is not unique (two equal singular values)";
	}
	return hs;
}

/** Unit normal of the least-squares plane through the flagged points (the eigenvector of the
 * smallest eigenvalue of their scatter), turned towards the origin (the reference camera);
 * zero for fewer than 3 points. */
Eigen::Vector3d planeNormal(const std::vector<Eigen::Vector3d>& points, const std::vector<uint8_t>& use)
{
	Eigen::Vector3d mean = Eigen::Vector3d::Zero();
	int n = 0;
	for (std::size_t i = 0; i < points.size(); i++)
		if (use[i])
		{
			mean += points[i];
			++n;
		}
	if (n < 3) return Eigen::Vector3d::Zero();
	mean /= n;
	Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
	for (std::size_t i = 0; i < points.size(); i++)
		if (use[i]) scatter += (points[i] - mean) * (points[i] - mean).transpose();
	Eigen::Vector3d normal = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvectors().col(0);
	if (normal.dot(mean) > 0) normal = -normal;
	return normal;
}

/* The best hypothesis (most good points, refined) is accepted when, in this order of diagnosis:
 * it triangulates at least min_triangulated points, its median parallax reaches
 * min_parallax_deg (else: pure rotation or a too short baseline; checked before ambiguity
 * because then t is unobservable and its hypotheses tie), no rival comes close (second /
 * best <= max_second_best_share, both before refinement; a rotation-like hypothesis is no
 * rival, see rival_parallax_share), it explains min_good_share of the inliers and has
 * min_triangulated valid points. */
TwoViewResult chooseMotion(TwoViewResult r, const detail::WeightedMatches& w, const PinholeIntrinsics& K, const TwoViewOptions& o)
{
	TwoViewFailure why = TwoViewFailure::None;
	std::string text;
	const auto hs = hypotheses(r, K, why, text);
	if (hs.empty()) return fail(std::move(r), why, text);
	std::vector<detail::HypothesisCheck> checks;
	std::size_t best = 0;
	for (std::size_t k = 0; k < hs.size(); k++)
	{
		checks.push_back(detail::checkMotion(hs[k], K, w, r.inliers, o));
		if (checks[k].good > checks[best].good) best = k;
	}
	// The linear estimates (8-point, DLT) are algebraic fits, several times less accurate than
	// the noise allows, and their gates cut good points: refine the best motion on the
	// model's inliers (Sampson error, re-gated on the refined motion: see refineMotion) and
	// check it again; keep whichever explains more points.
	std::vector<uint8_t> mask = r.inliers;
	const RelativeMotion refined = detail::refineMotion(hs[best], K, w, mask);
	auto rc = detail::checkMotion(refined, K, w, mask, o);
	const bool useRefined = rc.good >= checks[best].good;
	const auto& b = useRefined ? rc : checks[best];
	r.motion = useRefined ? refined : hs[best];
	if (useRefined)
	{
		r.inliers = mask;
		r.numInliers = static_cast<int>(std::count(mask.begin(), mask.end(), uint8_t{1}));
	}
	// Rivals of the best: the other hypotheses, less those that read the views as nearly a
	// rotation when the best reads a clear translation (rival_parallax_share,
	// rival_max_rotation_ratio).
	const double rotationDeg = Eigen::AngleAxisd(r.motion.R_cur_ref).angle() * 180.0 / M_PI;
	const bool translating = o.rivalParallaxShare > 0 && rotationDeg <= o.rivalMaxRotationRatio * b.medianParallaxDeg;
	const auto isRival = [&](std::size_t k)
	{
		const double p = checks[k].medianParallaxDeg;
		return k != best && !(translating && p < o.minParallaxDeg && p < o.rivalParallaxShare * b.medianParallaxDeg);
	};
	for (std::size_t k = 0; k < hs.size(); k++)
		if (isRival(k)) r.secondGood = std::max(r.secondGood, checks[k].good);
	r.bestGood = b.good;
	r.parallaxDeg = b.medianParallaxDeg;
	r.numTriangulated = b.numValid;
	std::ostringstream m;
	m << toString(r.model) << " (R_H = " << r.ratioH << ", shared inliers " << r.sharedInlierShare << "), " << r.numInliers
	  << " inliers, best motion " << b.good << " good / " << b.numValid << " triangulated, second " << r.secondGood
	  << ", median parallax " << b.medianParallaxDeg << " deg";
	const int minGood = std::max(o.minTriangulated, static_cast<int>(std::ceil(o.minGoodShare * r.numInliers)));
	if (b.good < o.minTriangulated) return fail(std::move(r), TwoViewFailure::TooFewTriangulated, m.str());
	if (b.medianParallaxDeg < o.minParallaxDeg) return fail(std::move(r), TwoViewFailure::LowParallax, m.str());
	if (r.secondGood > o.maxSecondBestShare * checks[best].good)
	{
		for (std::size_t k = 0; k < hs.size(); k++)
		{
			if (k != best && !(isRival(k) && checks[k].good > o.maxSecondBestShare * checks[best].good)) continue;
			const auto& c = k == best ? b : checks[k];
			TwoViewCandidate cand;
			cand.motion = k == best ? r.motion : hs[k];
			cand.points_ref = c.points_ref;
			cand.triangulated = c.valid;
			cand.good = c.good;
			cand.parallaxDeg = c.medianParallaxDeg;
			cand.planeNormal_ref = planeNormal(c.points_ref, c.valid);
			if (k == best) r.candidates.insert(r.candidates.begin(), std::move(cand));
			else
				r.candidates.push_back(std::move(cand));
		}
		return fail(std::move(r), TwoViewFailure::Ambiguous, m.str());
	}
	if (b.good < minGood || b.numValid < o.minTriangulated) return fail(std::move(r), TwoViewFailure::TooFewTriangulated, m.str());
	r.points_ref = b.points_ref;
	r.triangulated = b.valid;
	r.ok = true;
	r.message = "initialized: " + m.str();
	return r;
}
}  // namespace

TwoViewResult TwoViewInitializer::initialize(const TwoViewMatches& matches) const
{
	const detail::WeightedMatches w = weigh(matches, m_opts.sigmaPx);
	TwoViewResult r;
	const std::size_t n = w.size();
	if (n < static_cast<std::size_t>(m_opts.minMatches))
		return fail(r, TwoViewFailure::TooFewMatches, std::to_string(n) + " < min_matches = " + std::to_string(m_opts.minMatches));

	// Same draws for both models; each fit reads only its inputs, so running one of them in
	// another thread changes nothing in the result.
	const auto sets = detail::drawMinimalSets(n, m_opts.ransacIterations, m_opts.seed);
	detail::ModelFit fitH, fitF;
	if (m_opts.parallel)
	{
		auto futureH = std::async(std::launch::async, [&] { return detail::fitHomography(w, sets); });
		fitF = detail::fitFundamental(w, sets);
		fitH = futureH.get();
	}
	else
	{
		fitH = detail::fitHomography(w, sets);
		fitF = detail::fitFundamental(w, sets);
	}
	r.H_cur_ref = fitH.M;
	r.F_cur_ref = fitF.M;
	r.scoreH = fitH.score;
	r.scoreF = fitF.score;
	if (!(r.scoreH + r.scoreF > 0)) return fail(r, TwoViewFailure::TooFewMatches, "neither model fits any correspondence");
	r.ratioH = r.scoreH / (r.scoreH + r.scoreF);
	// F is degenerate when H explains (nearly) every F inlier: see homographyInlierShare.
	int both = 0;
	if (fitH.valid && fitF.valid)
		for (std::size_t i = 0; i < n; i++) both += fitH.inliers[i] & fitF.inliers[i];
	r.sharedInlierShare = fitF.numInliers > 0 ? static_cast<double>(both) / fitF.numInliers : 0.0;
	const bool useH = fitH.valid && (!fitF.valid || r.ratioH > m_opts.homographyRatio || r.sharedInlierShare >= m_opts.homographyInlierShare);
	r.model = useH ? TwoViewModel::Homography : TwoViewModel::Fundamental;
	const detail::ModelFit& fit = useH ? fitH : fitF;
	r.inliers = fit.inliers;
	r.numInliers = fit.numInliers;
	return chooseMotion(std::move(r), w, m_K, m_opts);
}

}  // namespace keygrid::sfm
