#include "LoopCorrection.h"
#include "LoopVerification.h"

#include <keygrid/sfm/Tracker.h>
#include <keygrid/loop/DataFiles.h>
#include <keygrid/loop/LoopCloser.h>
#include <keygrid/loop/SeenThroughCheck.h>
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/math/CMatrixFixed.h>

#include <algorithm>
#include <chrono>
#include <set>

namespace keygrid::loop
{
namespace
{
/** More covisible keyframes than any keyframe has: the reference score of a query is taken
 * over all of them. */
constexpr std::size_t kAllCovisibles = 1000;
/** Database candidates a query returns, best first. */
constexpr std::size_t kMaxCandidates = 10;
/** A candidate must score at least as high as the least similar covisible keyframe (ORB-SLAM's
 * normalisation): places look alike at different rates. */
constexpr double kMinScoreToReference = 1.0;
/** A candidate's group for the consistency check: it and this many of its best covisibles. */
constexpr std::size_t kCandidateGroupNeighbours = 10;
/** Ratio test of the verification matches: the best descriptor distance must be clearly
 * smaller than the second best, as repeated texture gives ambiguous matches. */
constexpr float kVerificationMatchRatio = 0.8f;
using detail::kLoopSideNeighbours;
/** Keyframes after a closed loop without detection: the map around it is still being joined. */
constexpr sfm::KeyFrameId kKeyFramesPausedAfterLoop = 5;
}  // namespace

Eigen::Isometry3d toIsometry(const mrpt::poses::CPose3D& p)
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	const auto R = p.getRotationMatrix();
	for (int i = 0; i < 3; i++)
	{
		for (int j = 0; j < 3; j++) T.linear()(i, j) = R(i, j);
		T.translation()(i) = p.m_coords[i];
	}
	return T;
}

mrpt::poses::CPose3D toCPose3D(const Eigen::Isometry3d& T)
{
	mrpt::math::CMatrixDouble33 R;
	mrpt::math::CVectorFixedDouble<3> t;
	// Re-orthonormalise: the optimiser works on quaternions, round-off accumulates.
	const Eigen::Matrix3d Rn = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
	for (int i = 0; i < 3; i++)
	{
		for (int j = 0; j < 3; j++) R(i, j) = Rn(i, j);
		t[i] = T.translation()(i);
	}
	return mrpt::poses::CPose3D::FromRotationAndTranslation(R, t);
}

const char* toString(LoopQueryOutcome o)
{
	switch (o)
	{
		case LoopQueryOutcome::Closed:
			return "closed";
		case LoopQueryOutcome::NoVocabulary:
			return "no_vocabulary";
		case LoopQueryOutcome::AfterLoop:
			return "after_loop";
		case LoopQueryOutcome::NoCandidate:
			return "no_candidate";
		case LoopQueryOutcome::NotConsistent:
			return "not_consistent";
		case LoopQueryOutcome::FewMatches:
			return "few_matches";
		case LoopQueryOutcome::RansacFailed:
			return "ransac_failed";
		case LoopQueryOutcome::ProjectionFailed:
			return "projection_failed";
		case LoopQueryOutcome::Implausible:
			return "implausible";
		case LoopQueryOutcome::MergePending:
			return "merge_pending";
		case LoopQueryOutcome::MergeSeenThrough:
			return "merge_seen_through";
		case LoopQueryOutcome::PoseGraphFailed:
			return "pose_graph_failed";
	}
	return "?";
}

VocabularyOptions LoopClosingOptions::trainingVocabularyDefaults()
{
	VocabularyOptions o;
	o.branching = 10;
	o.levels = 3;
	o.maxIterations = 10;
	o.seed = 1;
	o.threads = 1;
	return o;
}

RigidRansacOptions LoopClosingOptions::verificationRansacDefaults()
{
	RigidRansacOptions o;
	o.inlierThreshold = 0.04;
	o.minInliers = 40;
	o.maxIterations = 300;
	o.confidence = 0.999;
	o.refinementRounds = 5;
	o.estimateScale = false;
	o.seed = 42;
	return o;
}

core::OptionFields LoopClosingOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("enabled", enabled, "detect and correct loops");
	f.add("vocabulary", vocabulary, "default (shipped, ORB), train (first keyframes), or a file", R::nonEmpty());
	f.add("train_keyframes", trainKeyFrames, "keyframes that train the vocabulary", R::atLeast(2));
	f.add("vocabulary_branching", vocabularyOptions.branching, "k of the in-run (train) vocabulary", R::atLeast(2));
	f.add("vocabulary_levels", vocabularyOptions.levels, "L of the in-run (train) vocabulary", R::atLeast(1));
	f.add("min_keyframe_gap", minKeyFrameGap, "candidates at least this many keyframes older", R::atLeast(1));
	f.add("consistency", consistency, "consecutive keyframes agreeing on a candidate", R::atLeast(1));
	f.add("min_inliers", ransac.minInliers, "3D-3D RANSAC inliers to accept a loop", R::atLeast(3));
	f.add("inlier_threshold", ransac.inlierThreshold, "[m]", R::positive());
	f.add("covisibility_edge_min_weight", covisibilityEdgeMinWeight, "pose-graph covisibility edges");
	f.add("max_correction_base", maxCorrectionBase, "[m] largest loop correction: base +", R::atLeast(0));
	f.add("max_correction_ratio", maxCorrectionRatio, "... ratio x path between the keyframes", R::atLeast(0));
	f.add("max_correction_deg", maxCorrectionDeg, "[deg] largest loop rotation correction", R::positive());
	f.add("merge_consistency", mergeConsistency, "verified loops agreeing on a map merge", R::atLeast(1));
	f.add("merge_tolerance_m", mergeToleranceMetres, "[m] how far their alignments may differ", R::positive());
	f.add("merge_tolerance_deg", mergeToleranceDeg, "[deg] ... and in rotation", R::positive());
	f.add("merge_max_seen_through", mergeMaxSeenThrough, "largest share of landmarks seen through for a merge", R::inRange(0, 1));
	f.add("sim3_min_inliers", sim3.minInliers, "monocular: similarity RANSAC inliers (by reprojection) to accept a loop", R::atLeast(3));
	f.add("sim3_min_matches", sim3MinMatches, "monocular: loop landmarks the similarity must project onto keypoints", R::atLeast(3));
	return f;
}

void LoopClosingOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	fields().read(c, s);
	core::validateFields(*this, s);
	// The vocabulary's size and the verification's other parameters.
	ransac.validate(s);
	vocabularyOptions.validate(s);
	sim3.validate();
}

void LoopClosingOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	core::writeFields(*this, c, s);
}

LoopCloser::LoopCloser(
	sfm::SparseMap& map, sfm::LocalMapper& mapper, const LoopClosingOptions& opts, const sfm::MatcherOptions& matcher,
	const std::string& featureType)
	: m_map(map), m_mapper(mapper), m_opts(opts), m_matcher(matcher), m_consistency(opts.consistency)
{
	// The shipped vocabulary was trained on ORB descriptors (scripts/make-default-vocabulary.sh);
	// SIFT runs train their own in the run.
	if (opts.vocabulary == "train" || (opts.vocabulary == "default" && featureType != "orb")) return;
	m_vocabFile = opts.vocabulary == "default" ? findDataFile("vocabulary/keygrid_orb_k10_L4.bin") : opts.vocabulary;
	m_vocab = Vocabulary::load(m_vocabFile);
	const bool binary = m_vocab.descriptorType() == DescriptorType::Binary;
	if (binary != (featureType == "orb"))
		throw std::invalid_argument(
			"vocabulary '" + m_vocabFile + "' holds " + (binary ? "binary (ORB)" : "float (SIFT)") + " descriptors, but [features] type = " + featureType);
}

std::string LoopCloser::vocabularySource() const
{
	if (!m_vocabFile.empty()) return m_vocabFile;
	if (!m_vocabSource.empty()) return m_vocabSource;
	if (m_vocab.empty()) return "not trained yet (needs " + std::to_string(m_opts.trainKeyFrames) + " keyframes)";
	return "trained in the run on " + std::to_string(m_vocab.trainingImages()) + " keyframes";
}

void LoopCloser::trainIfReady()
{
	if (!m_vocab.empty() || static_cast<int>(m_map.numKeyFrames()) < m_opts.trainKeyFrames) return;
	std::vector<cv::Mat> descs;
	for (const auto& [id, kf] : m_map.keyframes()) descs.push_back(kf.features.descriptors);
	m_vocab = Vocabulary::train(descs, m_opts.vocabularyOptions);
	for (const auto& [id, kf] : m_map.keyframes())
	{
		m_db.add(id, m_vocab.transform(kf.features.descriptors));
		m_dbIds.insert(id);
	}
}

void LoopCloser::useVocabulary(Vocabulary vocabulary, const std::string& source)
{
	m_vocab = std::move(vocabulary);
	m_vocabFile.clear();
	m_vocabSource = source;
	m_db.clear();
	m_dbIds.clear();
}

void LoopCloser::indexKeyFrames()
{
	if (m_vocab.empty()) return;
	for (const auto& [id, kf] : m_map.keyframes())
		if (!m_db.contains(id))
		{
			m_db.add(id, m_vocab.transform(kf.features.descriptors));
			m_dbIds.insert(id);
		}
}

std::vector<sfm::KeyFrameId> LoopCloser::placeCandidates(const cv::Mat& descriptors, int maxCandidates) const
{
	std::vector<sfm::KeyFrameId> out;
	if (m_vocab.empty() || maxCandidates <= 0 || descriptors.empty()) return out;
	DatabaseQuery q;
	q.maxResults = static_cast<std::size_t>(maxCandidates);
	for (const auto& c : m_db.query(m_vocab.transform(descriptors), q))
		if (m_map.hasKeyFrame(c.id)) out.push_back(c.id);
	return out;
}

int LoopCloser::rejectedImplausible() const
{
	return static_cast<int>(std::count_if(
		m_queries.begin(), m_queries.end(), [](const LoopQueryRecord& q) { return q.outcome == LoopQueryOutcome::Implausible; }));
}

std::vector<LoopCloser::ScoredCandidate> LoopCloser::detect(sfm::KeyFrameId kfId, const BowVector& bow, LoopQueryRecord& rec)
{
	const auto t0 = std::chrono::steady_clock::now();
	// Reference: the lowest similarity with the covisible keyframes (ORB-SLAM's normalisation).
	const auto covis = m_map.bestCovisibles(kfId, kAllCovisibles);
	double ref = 1.0;
	for (auto c : covis)
		if (m_db.contains(c)) ref = std::min(ref, m_vocab.score(bow, m_db.bow(c)));
	if (covis.empty()) ref = 0.0;
	DatabaseQuery q;
	q.maxResults = kMaxCandidates;
	q.referenceScore = ref;
	q.minRatioToReference = kMinScoreToReference;
	q.exclude.insert(kfId);
	for (auto c : covis) q.exclude.insert(c);
	for (const auto& [id, kf] : m_map.keyframes())
		if (id + static_cast<sfm::KeyFrameId>(m_opts.minKeyFrameGap) > kfId) q.exclude.insert(id);
	const auto cands = m_db.query(bow, q);
	rec.querySeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	rec.referenceScore = ref;
	rec.candidates = static_cast<int>(cands.size());
	if (!cands.empty())
	{
		rec.bestCandidate = cands.front().id;
		rec.bestScore = cands.front().score;
	}
	std::vector<CandidateGroup> groups;
	for (const auto& c : cands)
	{
		if (!m_map.hasKeyFrame(c.id)) continue;
		CandidateGroup g;
		g.candidate = c.id;
		g.group.insert(c.id);
		for (auto n : m_map.bestCovisibles(c.id, kCandidateGroupNeighbours)) g.group.insert(n);
		groups.push_back(g);
	}
	const auto consistent = m_consistency.check(groups);
	std::vector<ScoredCandidate> out;
	for (const auto& c : cands)
		if (std::find(consistent.begin(), consistent.end(), c.id) != consistent.end()) out.push_back({c.id, c.score});
	return out;
}

bool LoopCloser::verify(sfm::KeyFrameId cur, sfm::KeyFrameId cand, const sfm::PinholeIntrinsics& K, Eigen::Isometry3d& T_cand_cur, LoopQueryRecord& rec)
{
	const auto& a = m_map.keyframe(cand);
	const auto& b = m_map.keyframe(cur);
	std::vector<Eigen::Vector3d> pa, pb;
	for (const auto& [i, j] : sfm::matchBruteForce(a.features, b.features, m_matcher, kVerificationMatchRatio))
	{
		const float da = a.features.depth[i], db = b.features.depth[j];
		if (da <= 0 || db <= 0) continue;
		pa.push_back(K.backProject(a.features.undistorted[i].x, a.features.undistorted[i].y, da));
		pb.push_back(K.backProject(b.features.undistorted[j].x, b.features.undistorted[j].y, db));
	}
	rec.matches = static_cast<int>(pa.size());
	const auto r = detail::verifiedByRansac(rec, m_opts.ransac.minInliers, [&] { return estimateRigidTransformRansac(pa, pb, m_opts.ransac); });
	if (!r) return false;
	T_cand_cur = r->T_a_b;
	return true;
}

bool LoopCloser::mergeConfirmed(
	sfm::KeyFrameId cur, sfm::KeyFrameId cand, const Eigen::Isometry3d& T_cand_cur, const sfm::PinholeIntrinsics& K, LoopQueryRecord& rec)
{
	const auto& c = m_map.keyframe(cur);
	const auto& l = m_map.keyframe(cand);
	if (c.mapId == l.mapId) return true;
	// A merge has no estimate to check the loop against (the two frames are unrelated), and
	// look-alike places (a corridor's repeated texture) pass verification now and then; a
	// true common place keeps verifying as the camera moves on. Each verified loop implies
	// where the current map lies in the other's frame: `merge_consistency` of them in a row
	// must agree.
	const Eigen::Isometry3d align = toIsometry(l.T_world_cam) * T_cand_cur * toIsometry(c.T_world_cam).inverse();
	// Free space: neither keyframe may see through the other side's landmarks.
	std::vector<sfm::KeyFrameId> loopSide = {cand}, curSide = {cur};
	for (const auto n : m_map.bestCovisibles(cand, kLoopSideNeighbours)) loopSide.push_back(n);
	for (const auto n : m_map.bestCovisibles(cur, kLoopSideNeighbours)) curSide.push_back(n);
	auto seen = countSeenThrough(m_map, loopSide, (toIsometry(l.T_world_cam) * T_cand_cur).inverse(), c, K);
	seen += countSeenThrough(m_map, curSide, toIsometry(l.T_world_cam).inverse() * align, l, K);
	rec.seenThroughRatio = seen.ratio();
	if (seen.ratio() > m_opts.mergeMaxSeenThrough)
	{
		rec.outcome = LoopQueryOutcome::MergeSeenThrough;
		return false;
	}
	bool agrees = false;
	if (m_merge && m_merge->currentMap == c.mapId && m_merge->loopMap == l.mapId)
	{
		const Eigen::Vector3d at = c.cameraCenter();
		const double dt = (align * at - m_merge->align * at).norm();
		const double dr = Eigen::AngleAxisd(align.linear().transpose() * m_merge->align.linear()).angle() * 180.0 / M_PI;
		agrees = dt <= m_opts.mergeToleranceMetres && dr <= m_opts.mergeToleranceDeg;
	}
	if (agrees)
		m_merge->count++;
	else
		m_merge = MergeHypothesis{c.mapId, l.mapId, align, 1};
	m_merge->align = align;
	if (m_merge->count < m_opts.mergeConsistency)
	{
		rec.outcome = LoopQueryOutcome::MergePending;
		return false;
	}
	m_merge.reset();
	return true;
}

bool LoopCloser::plausible(sfm::KeyFrameId cur, sfm::KeyFrameId cand, const Eigen::Isometry3d& T_cand_cur) const
{
	// A loop between two maps merges them: their frames are unrelated, nothing to compare.
	if (m_map.keyframe(cur).mapId != m_map.keyframe(cand).mapId) return true;
	// Path travelled between the two keyframes, along the keyframe sequence.
	double path = 0;
	std::optional<Eigen::Vector3d> last;
	for (auto it = m_map.keyframes().lower_bound(cand); it != m_map.keyframes().end() && it->first <= cur; ++it)
	{
		const Eigen::Vector3d c = it->second.cameraCenter();
		if (last) path += (c - *last).norm();
		last = c;
	}
	const Eigen::Isometry3d est = toIsometry(m_map.keyframe(cand).T_world_cam).inverse() * toIsometry(m_map.keyframe(cur).T_world_cam);
	const Eigen::Isometry3d E = est.inverse() * T_cand_cur;
	const double dt = E.translation().norm();
	const double dr = Eigen::AngleAxisd(E.linear()).angle() * 180.0 / M_PI;
	return dt <= m_opts.maxCorrectionBase + m_opts.maxCorrectionRatio * path && dr <= m_opts.maxCorrectionDeg;
}

namespace
{
using KeyFramePoses = std::map<sfm::KeyFrameId, Eigen::Isometry3d>;

/** Every keyframe's T_world_cam as an isometry. */
KeyFramePoses keyFramePoses(const sfm::SparseMap& map)
{
	KeyFramePoses poses;
	for (const auto& [id, kf] : map.keyframes()) poses[id] = toIsometry(kf.T_world_cam);
	return poses;
}
}  // namespace

/** Joins both sides of a closed loop: the landmarks of the loop keyframe's neighbourhood are
 * fused into the current keyframe's neighbourhood, whose covisibility is then updated. */
void detail::joinLoopSides(sfm::SparseMap& map, sfm::LocalMapper& mapper, sfm::KeyFrameId cur, sfm::KeyFrameId cand, const sfm::PinholeIntrinsics& K)
{
	std::set<sfm::LandmarkId> loopSide;
	std::vector<sfm::KeyFrameId> loopGroup = {cand}, curGroup = {cur};
	for (auto n : map.bestCovisibles(cand, kLoopSideNeighbours)) loopGroup.push_back(n);
	for (auto n : map.bestCovisibles(cur, kLoopSideNeighbours)) curGroup.push_back(n);
	for (auto id : loopGroup)
		for (auto l : map.keyframe(id).landmarks)
			if (l != sfm::kNoLandmark) loopSide.insert(l);
	const std::vector<sfm::LandmarkId> lms(loopSide.begin(), loopSide.end());
	for (auto id : curGroup)
		if (map.hasKeyFrame(id)) mapper.fuseLandmarks(id, lms, K);
	for (auto id : curGroup)
		if (map.hasKeyFrame(id)) map.updateCovisibility(id);
}

LoopClosureEvent LoopCloser::correct(sfm::KeyFrameId cur, sfm::KeyFrameId cand, const Eigen::Isometry3d& T_cand_cur, const sfm::PinholeIntrinsics& K)
{
	// Pose graph: every keyframe; consecutive keyframes and strong covisibility pairs keep
	// their current relative poses (weight 1), the loop edge brings the measured one.
	//
	// A loop between two maps (KeyFrame::mapId) merges them: the current keyframe's map is
	// first moved rigidly so that the loop measurement holds (its provisional frame may be
	// anywhere), then optimised with the rest. Odometry edges join consecutive keyframes of
	// one map only.
	const std::uint32_t curMap = m_map.keyframe(cur).mapId, loopMap = m_map.keyframe(cand).mapId;
	const bool merge = curMap != loopMap;
	const Eigen::Isometry3d align = merge ? toIsometry(m_map.keyframe(cand).T_world_cam) * T_cand_cur * toIsometry(m_map.keyframe(cur).T_world_cam).inverse()
										  : Eigen::Isometry3d::Identity();
	KeyFramePoses oldIso = keyFramePoses(m_map), newIso;
	PoseGraph g = detail::loopCorrectionGraph<PoseGraph>(m_map, oldIso, cur, cand, T_cand_cur, align, m_opts.covisibilityEdgeMinWeight);
	const auto summary = g.optimize(m_opts.poseGraph);

	LoopClosureEvent ev;
	ev.keyframe = cur;
	ev.loopKeyFrame = cand;
	ev.T_loop_cur = toCPose3D(T_cand_cur);
	if (!summary.usable) return ev;
	ev.mergedMap = merge;
	for (const auto& c : summary.corrections)
	{
		newIso[c.id] = c.T_world_kf_new;
		if (merge && m_map.keyframe(c.id).mapId == curMap) m_map.keyframe(c.id).mapId = loopMap;
		m_map.keyframe(c.id).T_world_cam = toCPose3D(c.T_world_kf_new);
		ev.newPoses[c.id] = m_map.keyframe(c.id).T_world_cam;
	}
	detail::moveLandmarksWithKeyFrames(m_map, oldIso, newIso);
	ev.correctionMetres = (newIso[cur].translation() - oldIso[cur].translation()).norm();
	detail::joinLoopSides(m_map, m_mapper, cur, cand, K);
	m_lastGraph = g;
	return ev;
}

std::optional<LoopClosureEvent> LoopCloser::closeVerifiedLoop(
	sfm::KeyFrameId kf, sfm::KeyFrameId cand, const Eigen::Isometry3d& T_cand_cur, std::size_t frameIndex, double score,
	const sfm::PinholeIntrinsics& K, LoopQueryRecord& rec, const std::optional<Sim3>& S_cand_cur)
{
	if (!plausible(kf, cand, T_cand_cur))
	{
		rec.outcome = LoopQueryOutcome::Implausible;
		return std::nullopt;
	}
	auto ev = S_cand_cur ? correctSim3(kf, cand, *S_cand_cur, K) : correct(kf, cand, T_cand_cur, K);
	if (ev.newPoses.empty())
	{
		rec.outcome = LoopQueryOutcome::PoseGraphFailed;
		return std::nullopt;
	}
	ev.frameIndex = frameIndex;
	ev.keyframeTimestamp = m_map.keyframe(kf).timestamp;
	ev.loopKeyFrameTimestamp = m_map.keyframe(cand).timestamp;
	ev.measuredDistance = T_cand_cur.translation().norm();
	ev.measuredAngleDeg = Eigen::AngleAxisd(T_cand_cur.linear()).angle() * 180.0 / M_PI;
	ev.score = score;
	ev.inliers = rec.inliers;
	m_lastLoopKf = kf;
	m_anyLoop = true;
	m_consistency.reset();
	rec.outcome = LoopQueryOutcome::Closed;
	return ev;
}

std::optional<LoopClosureEvent> LoopCloser::process(sfm::KeyFrameId kf, std::size_t frameIndex, const sfm::PinholeIntrinsics& K)
{
	if (!m_opts.enabled || !m_map.hasKeyFrame(kf)) return std::nullopt;
	// Keyframes culled by local mapping leave the database.
	for (auto it = m_dbIds.begin(); it != m_dbIds.end();)
		if (!m_map.hasKeyFrame(*it))
		{
			m_db.erase(*it);
			it = m_dbIds.erase(it);
		}
		else
			++it;
	LoopQueryRecord rec;
	rec.keyframe = kf;
	rec.frameIndex = frameIndex;
	if (m_vocab.empty())
	{
		trainIfReady();
		rec.outcome = LoopQueryOutcome::NoVocabulary;
		m_queries.push_back(rec);
		return std::nullopt;
	}
	const auto t0 = std::chrono::steady_clock::now();
	const BowVector bow = m_vocab.transform(m_map.keyframe(kf).features.descriptors);
	rec.querySeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	std::optional<LoopClosureEvent> out;
	if (m_anyLoop && kf <= m_lastLoopKf + kKeyFramesPausedAfterLoop)
		rec.outcome = LoopQueryOutcome::AfterLoop;
	else if (const auto cands = detect(kf, bow, rec); cands.empty())
		rec.outcome = rec.candidates ? LoopQueryOutcome::NotConsistent : LoopQueryOutcome::NoCandidate;
	else
	{
		// Monocular: every consistent candidate is verified, best score first, until one passes
		// (ORB-SLAM's ComputeSim3): the best-scoring keyframe of a revisited place is not always
		// the one whose landmarks match, e.g. the map's first keyframe, triangulated over a short
		// baseline. Its verification matches under the vocabulary's nodes and costs little. With
		// depth the best candidate only: brute-force matching each of up to kMaxCandidates would
		// cost several times the rest of loop closing per keyframe. The record keeps the passing
		// candidate, or the one that matched most.
		const std::size_t tries = m_opts.monocular ? cands.size() : 1;
		LoopQueryRecord best = rec;
		for (std::size_t i = 0; i < tries; i++)
		{
			const auto& c = cands[i];
			LoopQueryRecord r = rec;
			r.verifiedCandidate = c.id;
			r.verifiedCount = static_cast<int>(i) + 1;
			Eigen::Isometry3d T_cand_cur = Eigen::Isometry3d::Identity();
			Sim3 S_cand_cur;
			const bool verified = m_opts.monocular ? verifySim3(kf, c.id, K, S_cand_cur, r) : verify(kf, c.id, K, T_cand_cur, r);
			if (!verified)  // verification named the outcome
			{
				if (!best.verifiedCandidate || r.matches > best.matches) best = r;
				best.verifiedCount = r.verifiedCount;
				continue;
			}
			best = r;
			// The rigid part of the similarity places the current camera in the loop keyframe's
			// frame and units, as T_cand_cur does with depth.
			std::optional<Sim3> S;
			if (m_opts.monocular) T_cand_cur = (S = S_cand_cur)->rigid();
			if (mergeConfirmed(kf, c.id, T_cand_cur, K, best)) out = closeVerifiedLoop(kf, c.id, T_cand_cur, frameIndex, c.score, K, best, S);
			break;
		}
		rec = best;
		if (out) out->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	}
	m_queries.push_back(rec);
	m_db.add(kf, bow);
	m_dbIds.insert(kf);
	return out;
}

}  // namespace keygrid::loop
