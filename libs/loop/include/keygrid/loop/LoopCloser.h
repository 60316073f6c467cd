#pragma once
/** \file LoopCloser.h
 * Place recognition and loop correction for the SLAM system: each new keyframe is described
 * with the vocabulary tree, candidates come from the inverted index (scores normalised by the
 * keyframe's covisible neighbours), must be consistent over consecutive keyframes, and are
 * verified geometrically with depth (3D-3D RANSAC). A verified loop adds an edge to the SE(3)
 * keyframe pose graph; after optimisation landmarks follow their keyframes and the duplicated
 * landmarks around the loop are fused.
 *
 * Monocular maps (LoopClosingOptions::monocular; LoopCloser_monocular.cpp) have no depth and an
 * arbitrary, drifting scale: the loop is a similarity estimated from the matched map points of
 * both keyframes (Sim3Ransac.h) and verified by projecting the loop side's landmarks into the
 * current keyframe, and the correction is a Sim(3) pose graph (Sim3PoseGraph.h) whose scale
 * correction the landmarks follow.
 */
#include <keygrid/core/OptionFields.h>
#include <keygrid/loop/ConsistencyChecker.h>
#include <keygrid/loop/KeyFrameDatabase.h>
#include <keygrid/loop/PoseGraph.h>
#include <keygrid/loop/RigidRansac.h>
#include <keygrid/loop/Sim3Ransac.h>
#include <keygrid/loop/Vocabulary.h>
#include <keygrid/sfm/LocalMapper.h>
#include <keygrid/sfm/SparseMap.h>

#include <atomic>
#include <map>
#include <optional>
#include <set>
#include <string>

namespace keygrid::loop
{
struct LoopClosingOptions
{
	/** Detect and correct loops (Default: true) */
	bool enabled{true};
	/** "default": the vocabulary shipped in share/vocabulary (ORB features; with SIFT the
	 * in-run training is used instead), "train": trained on the first train_keyframes
	 * keyframes of the run, or a file from keygrid-vocab train (Default: default) */
	std::string vocabulary{"default"};
	/** Keyframes whose descriptors train the vocabulary when no file is given (Default: 10) */
	int trainKeyFrames{10};
	/** Tree shape used for that training (Default: branching 10, 3 levels = 1000 words,
	 * 10 k-means iterations, seed 1, one thread; trainingVocabularyDefaults()) */
	VocabularyOptions vocabularyOptions{trainingVocabularyDefaults()};
	/** Candidates must be at least this many keyframes older than the query (Default: 15) */
	int minKeyFrameGap{15};
	/** Consecutive keyframes that must agree on a candidate group (Default: 3) */
	int consistency{3};
	/** Geometric verification: RANSAC on matched keypoints with depth (Default: inliers within
	 * 0.04 m, 40 of them, at most 300 hypotheses, confidence 0.999, 5 refinement rounds, rigid,
	 * seed 42; verificationRansacDefaults()) */
	RigidRansacOptions ransac{verificationRansacDefaults()};
	/** Plausibility: the loop may move the current keyframe (relative to the loop keyframe) by
	 * at most max_correction_base + max_correction_ratio x the path travelled between them
	 * [m], and rotate it by at most max_correction_deg. Drift is a small fraction of the path;
	 * larger "corrections" come from look-alike places (Default: 0.1 m, 0.1, 10 deg) */
	double maxCorrectionBase{0.1}, maxCorrectionRatio{0.1}, maxCorrectionDeg{10.0};
	/** A loop between two maps (extend mode: a map started apart from the loaded one) merges
	 * them; this many verified loops in a row must place the current map alike, within
	 * merge_tolerance_m and merge_tolerance_deg (Default: 3, 0.05 m, 2 deg) */
	int mergeConsistency{3};
	double mergeToleranceMetres{0.05}, mergeToleranceDeg{2.0};
	/** Each of those loops: of the landmarks of either side that the other keyframe measures
	 * (SeenThroughCheck.h), at most this share may be seen through (Default: 0.01) */
	double mergeMaxSeenThrough{0.01};
	/** Covisibility edges of the pose graph need this many shared landmarks (Default: 100) */
	int covisibilityEdgeMinWeight{100};
	PoseGraphOptions poseGraph;
	/** A map without depth (monocular): loops are similarities verified by reprojection and
	 * corrected by a Sim(3) pose graph. Set by the application from [slam] sensor, not a
	 * [loop_closing] key (Default: false) */
	bool monocular{false};
	/** Monocular verification: RANSAC of the similarity between the matched map points of both
	 * keyframes, inliers by reprojection (Default: Sim3RansacOptions', sim3_min_inliers = 20) */
	Sim3RansacOptions sim3;
	/** Monocular verification: landmarks of the loop keyframe and its covisibles that, mapped
	 * into the current keyframe with the similarity, must match its keypoints (Default: 40) */
	int sim3MinMatches{40};

	/** The INI keys, with description and rule. */
	core::OptionFields fields();
	void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section);
	void saveToConfigFile(mrpt::config::CConfigFileBase& cfg, const std::string& section) const;

	/** The default of vocabularyOptions: a tree small enough for the few keyframes that train
	 * it in the run (train_keyframes). */
	static VocabularyOptions trainingVocabularyDefaults();
	/** The default of ransac: stricter than RigidRansacOptions' (more inliers, a tighter
	 * distance), as a wrong loop bends the whole map. */
	static RigidRansacOptions verificationRansacDefaults();
};

/** One closed loop, with the pose change of every keyframe (for the maps). */
struct LoopClosureEvent
{
	std::size_t frameIndex{0};
	sfm::KeyFrameId keyframe{0}, loopKeyFrame{0};
	double keyframeTimestamp{0}, loopKeyFrameTimestamp{0};  //!< [s], their frames' timestamps
	/** The verified relative pose T_loop_cur: distance between the two cameras [m] and the
	 * angle between them [deg] */
	double measuredDistance{0}, measuredAngleDeg{0};
	/** The verified measurement: pose of `keyframe` in `loopKeyFrame` */
	mrpt::poses::CPose3D T_loop_cur;
	double score{0};
	int inliers{0};
	double correctionMetres{0};  //!< how far the current keyframe moved
	/** Monocular: the scale the correction gave the current keyframe's neighbourhood (s_new /
	 * s_old, > 1: it grew); 1 for a rigid correction */
	double scaleCorrection{1};
	/** The loop joined two maps (KeyFrame::mapId): the current keyframe's map was moved into
	 * the loop keyframe's and now has its id. */
	bool mergedMap{false};
	double seconds{0};
	std::map<sfm::KeyFrameId, mrpt::poses::CPose3D> newPoses;
	/** Monocular: per keyframe of newPoses, the scale of its similarity (s_new / s_old): what
	 * it holds in its camera frame grows by this factor (its landmarks did). Empty for a
	 * rigid correction. */
	std::map<sfm::KeyFrameId, double> newScales;
};

/** Whether loop detection closed a loop at a keyframe, or why not. */
enum class LoopQueryOutcome
{
	Closed,
	NoVocabulary,  //!< in-run training not done yet
	AfterLoop,  //!< detection paused right after a loop
	NoCandidate,  //!< nothing above the covisible keyframes' score
	NotConsistent,  //!< no candidate group seen in enough consecutive keyframes
	FewMatches,  //!< geometric verification: too few matches with depth
	RansacFailed,  //!< geometric verification: too few RANSAC inliers
	ProjectionFailed,  //!< monocular verification: the similarity maps too few loop landmarks onto keypoints
	Implausible,  //!< correction larger than drift explains
	MergePending,  //!< a loop between two maps waiting for more that agree (mergeConsistency)
	MergeSeenThrough,  //!< a loop between two maps that puts landmarks where a keyframe sees free space
	PoseGraphFailed
};
/** "closed", "no_vocabulary", "after_loop", "no_candidate", "not_consistent", "few_matches",
 * "ransac_failed", "projection_failed", "implausible", "merge_pending", "merge_seen_through" or "pose_graph_failed"
 * (loop_queries.csv "outcome"). */
const char* toString(LoopQueryOutcome o);

/** What loop detection made of one keyframe (keygrid-slam writes them to loop_queries.csv):
 * why a loop was or was not closed there. */
struct LoopQueryRecord
{
	sfm::KeyFrameId keyframe{0};
	std::size_t frameIndex{0};
	LoopQueryOutcome outcome{LoopQueryOutcome::NoCandidate};
	/** The lowest BoW score between the keyframe and its covisible keyframes */
	double referenceScore{0};
	int candidates{0};  //!< database candidates above that reference
	sfm::KeyFrameId bestCandidate{0};  //!< valid when candidates > 0
	double bestScore{0};
	/** A consistent candidate sent to verification: the one that passed it, else the one with
	 * the most matches (matches, inliers and projectedMatches are its) */
	std::optional<sfm::KeyFrameId> verifiedCandidate;
	/** Consistent candidates sent to verification, best score first, until one passed (with
	 * depth only the best) */
	int verifiedCount{0};
	/** Verification: descriptor matches with depth on both sides (monocular: with a landmark on
	 * both sides), RANSAC inliers */
	int matches{0}, inliers{0};
	/** Monocular verification: loop landmarks the similarity projects onto current keypoints */
	int projectedMatches{0};
	double querySeconds{0};  //!< BoW transform + database query [s]
	/** A loop between two maps: the share of landmarks seen through (SeenThroughCheck.h) */
	double seenThroughRatio{0};
};

class LoopCloser
{
   public:
	/** `featureType` ("orb" or "sift") chooses between the shipped vocabulary and in-run
	 * training for vocabulary = default; a vocabulary file of another descriptor type throws. */
	LoopCloser(sfm::SparseMap& map, sfm::LocalMapper& mapper, const LoopClosingOptions& opts,
			   const sfm::MatcherOptions& matcher, const std::string& featureType = "orb");

	/** Where the vocabulary comes from: its file, or "trained on N keyframes" (for reports). */
	std::string vocabularySource() const;

	/** Handles keyframe `kf` (after its local mapping). Returns the event if a loop was closed. */
	std::optional<LoopClosureEvent> process(sfm::KeyFrameId kf, std::size_t frameIndex, const sfm::PinholeIntrinsics& K);

	/** Keyframes of the database that may show the same place as `descriptors`, best first
	 * (relocalization). Empty until the vocabulary exists. */
	std::vector<sfm::KeyFrameId> placeCandidates(const cv::Mat& descriptors, int maxCandidates) const;

	bool hasVocabulary() const { return !m_vocab.empty(); }
	/** The vocabulary file; empty when the vocabulary is trained in the run or was stored in a
	 * session (useVocabulary). */
	const std::string& vocabularyFile() const { return m_vocabFile; }
	/** Replaces the vocabulary (a loaded session's, trained in its run and stored in the file);
	 * `source` names it in reports. Clears the keyframe database. */
	void useVocabulary(Vocabulary vocabulary, const std::string& source);
	/** Adds every keyframe of the map that is not in the keyframe database yet (a map loaded
	 * from a session), its BoW vector computed from its descriptors. No-op without vocabulary. */
	void indexKeyFrames();
	/** The BoW vector of a keyframe in the database; nullptr when it is not there. */
	const BowVector* bowOf(sfm::KeyFrameId kf) const { return m_db.contains(kf) ? &m_db.bow(kf) : nullptr; }
	const Vocabulary& vocabulary() const { return m_vocab; }
	/** One record per keyframe handled by process(), in order. */
	const std::vector<LoopQueryRecord>& queries() const { return m_queries; }
	/** Loops that passed verification but were rejected as implausible (the queries with
	 * outcome Implausible; diagnostics). */
	int rejectedImplausible() const;
	/** The keyframe pose graph of the last correction (for posegraph.g2o). */
	const std::optional<PoseGraph>& lastPoseGraph() const { return m_lastGraph; }
	/** Monocular: the map's units are metres from now on (slam::MetricScale applied an
	 * estimate), so loops are verified and corrected at a fixed scale (Sim3RansacOptions::
	 * fixScale, Sim3PoseGraph::setScalesFixed); until then their scale is free. Safe to call
	 * from another thread than process(). */
	void setMetricUnits(bool metric) { m_metricUnits = metric; }
	bool metricUnits() const { return m_metricUnits; }

   private:
	void trainIfReady();
	struct ScoredCandidate
	{
		sfm::KeyFrameId id;
		double score;
	};
	/** The consistent candidates, best BoW score first; fills rec's candidate fields. */
	std::vector<ScoredCandidate> detect(sfm::KeyFrameId kf, const BowVector& bow, LoopQueryRecord& rec);
	/** True for a loop inside one map; for one between two maps (a merge), true once
	 * mergeConsistency verified loops in a row agree on where the current map lies (else
	 * rec.outcome = MergePending). */
	bool mergeConfirmed(
		sfm::KeyFrameId cur, sfm::KeyFrameId cand, const Eigen::Isometry3d& T_cand_cur, const sfm::PinholeIntrinsics& K, LoopQueryRecord& rec);
	/** False when the loop measurement disagrees with the estimate more than drift can explain. */
	bool plausible(sfm::KeyFrameId cur, sfm::KeyFrameId cand, const Eigen::Isometry3d& T_cand_cur) const;
	bool verify(sfm::KeyFrameId cur, sfm::KeyFrameId cand, const sfm::PinholeIntrinsics& K, Eigen::Isometry3d& T_cand_cur, LoopQueryRecord& rec);
	/** Plausibility check, pose-graph correction (the Sim(3) one when S_cand_cur is given, its
	 * rigid part being T_cand_cur) and the event; rec.outcome says which. */
	std::optional<LoopClosureEvent> closeVerifiedLoop(
		sfm::KeyFrameId kf, sfm::KeyFrameId cand, const Eigen::Isometry3d& T_cand_cur, std::size_t frameIndex,
		double score, const sfm::PinholeIntrinsics& K, LoopQueryRecord& rec, const std::optional<Sim3>& S_cand_cur = std::nullopt);
	LoopClosureEvent correct(sfm::KeyFrameId cur, sfm::KeyFrameId cand, const Eigen::Isometry3d& T_cand_cur, const sfm::PinholeIntrinsics& K);
	/** Monocular verification (LoopCloser_monocular.cpp): the similarity S_cand_cur from the
	 * keyframes' matched map points, checked by projection; false with rec.outcome set. */
	bool verifySim3(sfm::KeyFrameId cur, sfm::KeyFrameId cand, const sfm::PinholeIntrinsics& K, Sim3& S_cand_cur, LoopQueryRecord& rec);
	/** Loop-side landmarks that S_cand_cur maps onto keypoints of the current keyframe. */
	int countProjectedMatches(sfm::KeyFrameId cur, sfm::KeyFrameId cand, const Sim3& S_cand_cur, const sfm::PinholeIntrinsics& K) const;
	/** The Sim(3) counterpart of correct(): keyframes take the rigid part of their corrected
	 * similarity, landmarks follow their keyframe's similarity (scale included). */
	LoopClosureEvent correctSim3(sfm::KeyFrameId cur, sfm::KeyFrameId cand, const Sim3& S_cand_cur, const sfm::PinholeIntrinsics& K);

	sfm::SparseMap& m_map;
	sfm::LocalMapper& m_mapper;
	LoopClosingOptions m_opts;
	sfm::MatcherOptions m_matcher;
	Vocabulary m_vocab;
	std::string m_vocabFile;  //!< empty: trained in the run or loaded with a session
	std::string m_vocabSource;  //!< useVocabulary()'s source, for reports
	KeyFrameDatabase m_db;
	std::set<sfm::KeyFrameId> m_dbIds;
	ConsistencyChecker m_consistency;
	std::optional<PoseGraph> m_lastGraph;
	/** Verified loops between two maps so far, agreeing on align = T_loopMap_currentMap. */
	struct MergeHypothesis
	{
		std::uint32_t currentMap{0}, loopMap{0};
		Eigen::Isometry3d align{Eigen::Isometry3d::Identity()};
		int count{0};
	};
	std::optional<MergeHypothesis> m_merge;
	sfm::KeyFrameId m_lastLoopKf{0};
	bool m_anyLoop{false};
	std::atomic<bool> m_metricUnits{false};  //!< see setMetricUnits()
	std::vector<LoopQueryRecord> m_queries;
};

/** CPose3D <-> Eigen isometry. */
Eigen::Isometry3d toIsometry(const mrpt::poses::CPose3D& p);
mrpt::poses::CPose3D toCPose3D(const Eigen::Isometry3d& T);

}  // namespace keygrid::loop
