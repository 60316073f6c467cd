#include <keygrid/sfm/Tracker.h>

#include "detail/TrackerConstants.h"

#include <algorithm>
#include <ctime>
#include <numeric>
#include <set>
#include <stdexcept>
#include <unordered_set>

namespace keygrid::sfm
{
namespace
{
/** Fewest matches a pose refinement is run on: with fewer, the six pose parameters are barely
 * constrained and an outlier cannot be told from an inlier. */
constexpr std::size_t kMinRefinementMatches = 6;
/** The motion-model search is repeated in a wider window when it finds fewer than this many
 * times min_matches_prediction: a window that caught so few has missed a change of motion. */
constexpr int kWideSearchBelowFactor = 2;
/** Radius of that wider search, a multiple of radius_prediction. */
constexpr float kWideSearchRadiusFactor = 2.5f;
/** A relocalization needs this many times min_inliers after its PnP: a look-alike place
 * (repeated texture) gives a few dozen consistent matches, a true revisit hundreds. */
constexpr int kRelocalizationInlierFactor = 2;
/** After a PnP pose the local map is the PnP keyframe and this many of its best covisible
 * keyframes (until updateLocalKeyFrames rebuilds it from the frame's matches). */
constexpr int kPnpCovisibleKeyFrames = 10;
/** Covisible neighbours of each keyframe sharing landmarks with the frame that widen the
 * local map (up to local_keyframes). */
constexpr int kLocalMapNeighbours = 5;
/** keyframe_tracked_ratio while the map has a single keyframe (ORB-SLAM2's 0.4): the second
 * keyframe waits for a wider baseline to the first than later keyframes do. */
constexpr double kTrackedRatioWithOneKeyFrame = 0.4;

/** Inliers a pose needs before the local-map search (motion model, or PnP on the reference
 * keyframe): half of min_inliers, the search adds the matches that reach min_inliers. */
int firstStageMinInliers(const TrackerOptions& o) { return o.minInliers / 2; }

double threadCpuSeconds()
{
	timespec ts{};
	clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
	return ts.tv_sec + 1e-9 * ts.tv_nsec;
}
}  // namespace

const char* toString(TrackingMethod m)
{
	switch (m)
	{
		case TrackingMethod::Init:
			return "init";
		case TrackingMethod::Prediction:
			return "prediction";
		case TrackingMethod::Pnp:
			return "pnp";
		case TrackingMethod::Relocalization:
			return "relocalization";
		case TrackingMethod::Lost:
			return "lost";
	}
	return "?";
}

Tracker::Tracker(SparseMap& map, const TrackerOptions& opts) : m_map(map), m_opts(opts)
{
	if (opts.hoc.enabled)
	{
		m_hoc.emplace(opts.hoc);
		m_hoc->setResidualGate(opts.pose);
	}
}

void Tracker::deferKeyFramesWhile(std::function<bool()> mappingBusy, double weakRatio)
{
	if (!(weakRatio > 0 && weakRatio <= 1))
		throw std::invalid_argument("Tracker::deferKeyFramesWhile: weakRatio = " + std::to_string(weakRatio) + " (must be in (0, 1])");
	m_mappingBusy = std::move(mappingBusy);
	m_deferWeakRatio = weakRatio;
}

Tracker::KeyFrameNeed Tracker::insertUnlessDeferred(bool wanted, bool timeout, int inliers, int refMatches) const
{
	if (!wanted) return KeyFrameNeed::No;
	if (timeout || !m_mappingBusy || !m_mappingBusy()) return KeyFrameNeed::Yes;
	// Local mapping still busy with the last keyframe: wait for it unless tracking is weak.
	return inliers < m_deferWeakRatio * refMatches ? KeyFrameNeed::YesWhileMappingBusy : KeyFrameNeed::No;
}

bool Tracker::hocUsable(LandmarkId id, const Current& cur)
{
	// Untimed: callers time whole selection passes, as a thread-CPU clock read costs more than
	// the selection of one landmark.
	return !m_hoc || hocUsable(m_map.landmark(id), cur);
}

bool Tracker::hocUsable(Landmark& lm, const Current& cur)
{
	return !m_hoc || m_hoc->usable(lm, m_map, translationOf(cur.T_world_cam), m_hocRelaxed);
}

TrackedFrame Tracker::track(const core::Frame& frame, FrameFeatures features)
{
	TrackedFrame out;
	out.index = frame.index;
	out.timestamp = frame.timestamp;
	Current cur;
	cur.frame = &frame;
	cur.features = std::move(features);
	cur.matches.assign(cur.features.size(), kNoLandmark);
	m_K = cur.features.camera.pinhole();

	if (m_state == TrackingState::NotInitialized)
	{
		if (!(m_opts.monocular ? initializeMonocular(cur, out) : initialize(cur, out)))
		{
			out.method = TrackingMethod::Lost;
			out.T_world_cam = m_lastPose;
		}
		return out;
	}

	// Rolling shutter: keypoints moved to the frame's timestamp, first with the rates of the
	// last step (the motion model's), after tracking with those of the step just estimated.
	std::optional<RollingShutterCompensator> rs;
	if (m_opts.rollingShutterReadout > 0)
	{
		rs.emplace(cur.features, m_opts.rollingShutterReadout);
		if (m_state == TrackingState::Ok && m_velocity && m_velocityDt > 0)
			rs->apply(cur.features, ratesFromRelativePose(*m_velocity, m_velocityDt), m_K);
	}

	bool ok = attempt(cur, out);
	// HOC: a strict selection (select_threshold above p(0)) leaves only confirmed points; after
	// fast motion into new ground, or once lost, those may be too few while the points of the
	// newest keyframes still wait for their confirming match. Retry with every point whose
	// evidence is not negative in the camera's bin (p(n) > p(0)): tracking must not stop on
	// the selection. Visible/found counters of the failed attempt stay counted.
	if (!ok && m_hoc && m_hoc->hasFallback())
	{
		const auto method = out.method;
		cur.matches.assign(cur.features.size(), kNoLandmark);
		cur.inliers = cur.localMapInView = 0;
		cur.hocVisible.clear();
		cur.hocExcluded.clear();
		cur.matchedBeforeLocalMap.clear();
		m_hocRelaxed = true;
		ok = attempt(cur, out);
		m_hocRelaxed = false;
		out.hocFallback = ok;
		if (!ok) out.method = method;
	}

	if (ok && rs && m_state == TrackingState::Ok) recompensateRollingShutter(cur, *rs);

	out.matches = static_cast<int>(std::count_if(cur.matches.begin(), cur.matches.end(), [](LandmarkId l) { return l != kNoLandmark; }));
	out.inliers = cur.inliers;
	if (ok)
	{
		m_velocity = cur.T_world_cam - m_lastPose;  // inv(last) * cur
		m_velocityDt = m_state == TrackingState::Ok ? stepDuration(frame.timestamp) : 0.0;
		m_lastPose = cur.T_world_cam;
		m_lastTimestamp = frame.timestamp;
		m_state = TrackingState::Ok;
		m_framesLost = 0;
		if (out.method != TrackingMethod::Relocalization && cur.localMapInView > 0)
		{
			m_recentShares.push_back(static_cast<double>(cur.inliers) / cur.localMapInView);
			if (m_recentShares.size() > kRecentShares) m_recentShares.pop_front();
		}
		m_lastInliers.clear();
		// Exactly sized: the run keeps these lists for every frame.
		const auto inliers = static_cast<std::size_t>(std::count_if(cur.matches.begin(), cur.matches.end(), [](LandmarkId l) { return l != kNoLandmark; }));
		out.observedLandmarks.reserve(inliers);
		out.observations.reserve(inliers);
		for (std::size_t i = 0; i < cur.matches.size(); i++)
		{
			const LandmarkId l = cur.matches[i];
			if (l == kNoLandmark) continue;
			m_lastInliers.push_back(l);
			FrameObservation ob;
			ob.u = cur.features.undistorted[i].x;
			ob.v = cur.features.undistorted[i].y;
			ob.depth = cur.features.depth[i];
			ob.invSigma = 1.0 / cur.features.levelScale[cur.features.keypoints[i].octave];
			out.observedLandmarks.push_back(l);
			out.observations.push_back(ob);
		}
		if (m_hoc) updateHoc(cur, out);
		if (const auto need = m_insertKeyFrames ? needKeyFrame(cur) : KeyFrameNeed::No; need != KeyFrameNeed::No)
		{
			out.keyframe = createKeyFrame(cur);
			out.newKeyFrame = true;
			out.keyFrameWhileMappingBusy = need == KeyFrameNeed::YesWhileMappingBusy;
		}
	}
	else
	{
		m_state = TrackingState::Lost;
		m_velocity.reset();
		++m_framesLost;
		out.method = TrackingMethod::Lost;
		cur.T_world_cam = m_lastPose;  // best guess until relocalized
	}
	out.tracked = ok;
	out.T_world_cam = cur.T_world_cam;
	if (m_map.hasKeyFrame(m_refKf))
	{
		out.reference = m_refKf;
		out.T_ref_cam = cur.T_world_cam - m_map.keyframe(m_refKf).T_world_cam;
		out.hasReference = true;
		m_lastRelative.emplace(m_refKf, out.T_ref_cam);
	}
	else
		m_lastRelative.reset();
	return out;
}

std::optional<double> Tracker::recentShareMedian() const
{
	if (m_recentShares.empty()) return std::nullopt;
	return medianShare({m_recentShares.begin(), m_recentShares.end()});
}

double Tracker::stepDuration(double timestamp) const
{
	// Rates are averaged over the step: beyond a few frames (dropped frames, a pause in the
	// input) the average says little about the motion during one exposure.
	constexpr double kMaxStep = 0.1;
	const double dt = timestamp - m_lastTimestamp;
	return dt > 0 && dt <= kMaxStep ? dt : 0.0;
}

void Tracker::recompensateRollingShutter(Current& cur, const RollingShutterCompensator& rs)
{
	const double dt = stepDuration(cur.frame->timestamp);
	if (dt <= 0) return;
	rs.apply(cur.features, ratesFromRelativePose(cur.T_world_cam - m_lastPose, dt), m_K);
	cur.inliers = refinePose(cur);
}

bool Tracker::attempt(Current& cur, TrackedFrame& out)
{
	bool ok = false;
	if (m_state == TrackingState::Ok)
	{
		cur.T_world_cam = m_velocity ? m_lastPose + *m_velocity : m_lastPose;
		// Without a motion prior (right after initialisation or relocalization) the camera may
		// have moved tens of pixels: match descriptors against the reference keyframe first.
		if (!m_velocity)
		{
			ok = trackByPnp(cur, m_refKf, firstStageMinInliers(m_opts));
			out.method = TrackingMethod::Pnp;
		}
		if (!ok)
		{
			cur.matches.assign(cur.features.size(), kNoLandmark);
			cur.T_world_cam = m_velocity ? m_lastPose + *m_velocity : m_lastPose;
			ok = trackByPrediction(cur);
			out.method = TrackingMethod::Prediction;
		}
		if (!ok)
		{
			cur.matches.assign(cur.features.size(), kNoLandmark);
			cur.T_world_cam = m_lastPose;
			ok = trackByPnp(cur, m_refKf, firstStageMinInliers(m_opts));
			out.method = TrackingMethod::Pnp;
		}
	}
	else
	{
		ok = relocalize(cur);
		out.method = TrackingMethod::Relocalization;
	}
	if (ok)
	{
		updateLocalKeyFrames(cur);
		cur.inliers = trackLocalMap(cur, m_opts.radiusLocalMap);
		ok = cur.inliers >= m_opts.minInliers;
		// A look-alike place matches a few dozen landmarks of a local map that shows hundreds
		// in view; the true place matches a good share of them.
		if (ok && out.method == TrackingMethod::Relocalization)
		{
			ok = cur.inliers >= requiredRelocalizationShare(m_opts, {m_recentShares.begin(), m_recentShares.end()}) * cur.localMapInView;
			out.relocalizationKeyFrame = m_refKf;
			out.relocalizedByPlaceRecognition = m_relocRecognized;
		}
	}

	return ok;
}

void Tracker::onMapCorrected()
{
	mrpt::poses::CPose3D T_world_ref;
	if (m_lastRelative && m_map.poseOf(m_lastRelative->first, T_world_ref)) m_lastPose = T_world_ref + m_lastRelative->second;
}

void Tracker::startNewMap()
{
	std::uint32_t last = 0;
	for (const auto& [id, kf] : m_map.keyframes()) last = std::max(last, kf.mapId);
	m_newMapId = m_map.keyframes().empty() ? 0 : last + 1;
	m_state = TrackingState::NotInitialized;
	m_velocity.reset();
	m_lastRelative.reset();
	m_monoRef.reset();
}

bool Tracker::initialize(Current& cur, TrackedFrame& out)
{
	const int withDepth = static_cast<int>(std::count_if(cur.features.depth.begin(), cur.features.depth.end(), [](float d) { return d > 0; }));
	if (withDepth < m_opts.minInitFeatures) return false;
	cur.T_world_cam = mrpt::poses::CPose3D();  // the first keyframe defines the world frame
	KeyFrame kf = keyFrameOf(cur);
	kf.mapId = m_newMapId;
	const KeyFrameId id = m_map.addKeyFrame(std::move(kf)).id;
	const auto& f = m_map.keyframe(id).features;
	for (std::size_t i = 0; i < f.size(); i++)
		if (f.depth[i] > 0)
			m_map.addLandmark(m_K.backProject(f.undistorted[i].x, f.undistorted[i].y, f.depth[i]), id, static_cast<int>(i));
	if (m_hoc) m_hoc->confirmInitialMap(m_map, id);
	startTrackingOnNewMap(cur, out, {id}, static_cast<int>(m_map.numLandmarks()));
	return true;
}

void Tracker::startTrackingOnNewMap(const Current& cur, TrackedFrame& out, std::vector<KeyFrameId> localKfs, int landmarks)
{
	const KeyFrameId newest = localKfs.front();
	m_refKf = newest;
	m_lastKfFrame = cur.frame->index;
	m_localKfs = std::move(localKfs);
	m_lastPose = cur.T_world_cam;
	m_lastTimestamp = cur.frame->timestamp;
	m_velocity.reset();
	m_velocityDt = 0;
	m_state = TrackingState::Ok;
	out.tracked = true;
	out.method = TrackingMethod::Init;
	out.inliers = out.matches = landmarks;
	out.newKeyFrame = true;
	out.keyframe = newest;
	out.T_world_cam = cur.T_world_cam;
	out.reference = newest;
	out.hasReference = true;
	m_lastInliers.clear();
}

std::vector<ProjectedLandmark> Tracker::projectLocalLandmarks(Current& cur, bool forLocalMap)
{
	// Hash sets: this runs twice per frame over every landmark of the local keyframes.
	const std::unordered_set<LandmarkId> already(cur.matches.begin(), cur.matches.end());
	std::unordered_set<LandmarkId> seen;
	seen.reserve(4096);
	std::vector<ProjectedLandmark> inView;
	// The landmarks of inView, found once: the map is a std::map (id order keeps runs
	// deterministic), and each further lookup walks the tree again.
	std::vector<Landmark*> inViewLm;
	const auto T_cam_world = -cur.T_world_cam;
	const Eigen::Vector3d center = translationOf(cur.T_world_cam);
	for (KeyFrameId kfId : m_localKfs)
	{
		if (!m_map.hasKeyFrame(kfId)) continue;
		for (LandmarkId id : m_map.keyframe(kfId).landmarks)
		{
			if (id == kNoLandmark || already.count(id) || !seen.insert(id).second) continue;
			Landmark* lm = m_map.findLandmark(id);
			if (!lm) continue;
			ProjectedLandmark p;
			if (projectLandmark(*lm, T_cam_world, center, m_K, cur.features, m_opts.matcher, p))
			{
				inView.push_back(p);
				inViewLm.push_back(lm);
			}
		}
	}
	// HOC selection (everything passes without HOC), timed as one pass.
	const double t0 = m_hoc ? threadCpuSeconds() : 0.0;
	std::vector<ProjectedLandmark> out;
	out.reserve(inView.size());
	for (std::size_t i = 0; i < inView.size(); i++)
	{
		const auto& p = inView[i];
		if (!hocUsable(*inViewLm[i], cur))
		{
			if (forLocalMap) cur.hocExcluded.push_back(p);
			continue;
		}
		if (forLocalMap) inViewLm[i]->visibleCount++;
		out.push_back(p);
	}
	if (m_hoc) m_hocSelectionSeconds += threadCpuSeconds() - t0;
	return out;
}

int Tracker::refinePose(Current& cur, bool anchored)
{
	std::vector<PoseObservation> obs;
	std::vector<int> kpOf;
	for (std::size_t i = 0; i < cur.matches.size(); i++)
	{
		const Landmark* lm = cur.matches[i] == kNoLandmark ? nullptr : m_map.findLandmark(cur.matches[i]);
		if (!lm) continue;
		const auto& f = cur.features;
		PoseObservation o;
		o.p_world = lm->p_world;
		o.uv = {f.undistorted[i].x, f.undistorted[i].y};
		o.depth = f.depth[i];
		o.invSigma = 1.0 / f.levelScale[f.keypoints[i].octave];
		obs.push_back(o);
		kpOf.push_back(static_cast<int>(i));
	}
	if (obs.size() < kMinRefinementMatches) return 0;
	PoseOptimizerResult r;
	if (anchored && m_opts.anchorMinKeyFrames > 0)
	{
		// Anchors: landmarks the map has confirmed from several keyframes (PoseOptimizer.h).
		std::vector<char> isAnchor(obs.size(), 0);
		for (std::size_t k = 0; k < obs.size(); k++)
			isAnchor[k] = static_cast<int>(m_map.landmark(cur.matches[kpOf[k]]).observations.size()) >= m_opts.anchorMinKeyFrames;
		r = optimizePoseAnchored(cur.T_world_cam, obs, isAnchor, m_K, m_opts.pose, m_opts.anchorChi2Factor, m_opts.anchorMinCount);
	}
	else
		r = optimizePose(cur.T_world_cam, obs, m_K, m_opts.pose);
	for (std::size_t k = 0; k < obs.size(); k++)
		if (!r.inlier[k]) cur.matches[kpOf[k]] = kNoLandmark;
	return r.inliers;
}

bool Tracker::trackByPrediction(Current& cur)
{
	if (m_localKfs.empty()) m_localKfs = {m_refKf};
	auto cands = projectLocalLandmarks(cur, false);
	int n = searchByProjection(cur.features, cands, m_opts.radiusPrediction, m_opts.matcher, cur.matches);
	// Few matches in the window: the motion changed; search wider before giving up.
	if (n < kWideSearchBelowFactor * m_opts.minMatchesPrediction)
	{
		cur.matches.assign(cur.features.size(), kNoLandmark);
		n = searchByProjection(cur.features, cands, kWideSearchRadiusFactor * m_opts.radiusPrediction, m_opts.matcher, cur.matches);
	}
	if (n < m_opts.minMatchesPrediction) return false;
	return refinePose(cur) >= firstStageMinInliers(m_opts);
}

bool Tracker::trackByPnp(Current& cur, KeyFrameId kfId, int minRefinedInliers)
{
	if (!m_map.hasKeyFrame(kfId)) return false;
	const auto& kf = m_map.keyframe(kfId);
	const auto pairs = matchBruteForce(cur.features, kf.features, m_opts.matcher);
	std::vector<Eigen::Vector3d> pw;
	std::vector<Eigen::Vector2d> px;
	std::vector<std::pair<int, LandmarkId>> link;
	for (const auto& [i, j] : pairs)
	{
		const LandmarkId lm = kf.landmarks[j];
		if (lm != kNoLandmark && m_map.hasLandmark(lm)) link.emplace_back(i, lm);
	}
	if (m_hoc)
	{
		const double t0 = threadCpuSeconds();
		link.erase(std::remove_if(link.begin(), link.end(), [&](const auto& l) { return !hocUsable(l.second, cur); }), link.end());
		m_hocSelectionSeconds += threadCpuSeconds() - t0;
	}
	for (const auto& [i, lm] : link)
	{
		pw.push_back(m_map.landmark(lm).p_world);
		px.emplace_back(cur.features.undistorted[i].x, cur.features.undistorted[i].y);
	}
	const auto res = solvePnpRansac(pw, px, m_K, m_opts.pnp);
	if (!res.ok) return false;
	cur.T_world_cam = res.T_world_cam;
	cur.matches.assign(cur.features.size(), kNoLandmark);
	for (int k : res.inliers) cur.matches[link[k].first] = link[k].second;
	const int inl = refinePose(cur);
	if (inl < minRefinedInliers) return false;
	m_localKfs = {kfId};
	for (KeyFrameId n : m_map.bestCovisibles(kfId, kPnpCovisibleKeyFrames)) m_localKfs.push_back(n);
	return true;
}

bool Tracker::relocalize(Current& cur)
{
	// Place recognition first (any keyframe of the map, however old), then the newest
	// keyframes: after a short loss the camera is usually near where it was.
	std::vector<KeyFrameId> ids;
	if (m_placeRecognizer && m_opts.relocalizationBowCandidates > 0)
		ids = m_placeRecognizer(cur.features, m_opts.relocalizationBowCandidates);
	const std::set<KeyFrameId> recognized(ids.begin(), ids.end());
	int newest = 0;
	for (auto it = m_map.keyframes().rbegin(); it != m_map.keyframes().rend() && newest < m_opts.relocalizationCandidates; ++it, ++newest)
		if (!recognized.count(it->first)) ids.push_back(it->first);
	for (KeyFrameId id : ids)
	{
		if (!m_map.hasKeyFrame(id)) continue;
		cur.matches.assign(cur.features.size(), kNoLandmark);
		cur.T_world_cam = m_map.keyframe(id).T_world_cam;
		if (trackByPnp(cur, id, kRelocalizationInlierFactor * m_opts.minInliers))
		{
			m_refKf = id;
			m_relocRecognized = recognized.count(id) > 0;
			return true;
		}
	}
	return false;
}

void Tracker::updateLocalKeyFrames(const Current& cur)
{
	std::map<KeyFrameId, int> counts;
	for (LandmarkId l : cur.matches)
	{
		if (l == kNoLandmark || !m_map.hasLandmark(l)) continue;
		for (const auto& [kf, kp] : m_map.landmark(l).observations) counts[kf]++;
	}
	if (counts.empty()) return;
	std::vector<std::pair<int, KeyFrameId>> v;
	for (const auto& [kf, c] : counts) v.emplace_back(-c, kf);
	std::sort(v.begin(), v.end());
	m_localKfs.clear();
	std::set<KeyFrameId> in;
	for (const auto& [c, kf] : v)
	{
		if (static_cast<int>(m_localKfs.size()) >= m_opts.localKeyFrames) break;
		if (in.insert(kf).second) m_localKfs.push_back(kf);
	}
	// Neighbours of the strongest ones widen the local map.
	const std::size_t base = m_localKfs.size();
	for (std::size_t i = 0; i < base && static_cast<int>(m_localKfs.size()) < m_opts.localKeyFrames; i++)
		for (KeyFrameId n : m_map.bestCovisibles(m_localKfs[i], kLocalMapNeighbours))
			if (static_cast<int>(m_localKfs.size()) < m_opts.localKeyFrames && in.insert(n).second) m_localKfs.push_back(n);
	// The reference keyframe: the one sharing most landmarks.
	m_refKf = v.front().second;
}

int Tracker::trackLocalMap(Current& cur, float radius)
{
	// Landmarks matched before this stage were in view too.
	for (LandmarkId l : cur.matches)
		if (Landmark* lm = l == kNoLandmark ? nullptr : m_map.findLandmark(l)) lm->visibleCount++;
	cur.matchedBeforeLocalMap = cur.matches;
	cur.hocExcluded.clear();
	auto cands = projectLocalLandmarks(cur, true);
	cur.localMapInView = static_cast<int>(cands.size() + std::count_if(cur.matches.begin(), cur.matches.end(), [](LandmarkId l) { return l != kNoLandmark; }));
	searchByProjection(cur.features, cands, radius, m_opts.matcher, cur.matches);
	if (m_hoc) cur.hocVisible = cands;
	const int inl = refinePose(cur, true);
	for (LandmarkId l : cur.matches)
		if (Landmark* lm = l == kNoLandmark ? nullptr : m_map.findLandmark(l)) lm->foundCount++;
	return inl;
}

void Tracker::updateHoc(Current& cur, TrackedFrame& out)
{
	// Thread CPU time: the cost of the bookkeeping itself, not of waiting for a busy core.
	const double t0 = threadCpuSeconds();
	// Matches of the earlier stages that the final refinement rejected were in view too.
	const auto T_cam_world = -cur.T_world_cam;
	const Eigen::Vector3d centre = translationOf(cur.T_world_cam);
	const std::unordered_set<LandmarkId> finalMatches(cur.matches.begin(), cur.matches.end());
	for (LandmarkId id : cur.matchedBeforeLocalMap)
	{
		const Landmark* lm = id == kNoLandmark || finalMatches.count(id) ? nullptr : m_map.findLandmark(id);
		if (!lm) continue;
		ProjectedLandmark p;
		if (projectLandmark(*lm, T_cam_world, centre, m_K, cur.features, m_opts.matcher, p)) cur.hocVisible.push_back(p);
	}
	out.hoc = m_hoc->update(m_map, cur.features, cur.matches, cur.hocVisible, cur.hocExcluded, cur.frame->depth, centre,
							m_opts.radiusLocalMap, m_opts.matcher);
	out.hocSeconds = threadCpuSeconds() - t0 + m_hocSelectionSeconds;
	m_hocSelectionSeconds = 0;
}

Tracker::KeyFrameNeed Tracker::needKeyFrame(const Current& cur) const
{
	if (m_opts.monocular) return needKeyFrameMonocular(cur);
	const int sinceLast = static_cast<int>(cur.frame->index - m_lastKfFrame);
	// Landmarks of the reference keyframe also seen by other keyframes (ORB-SLAM2's "3
	// observations", where an RGB-D observation counts twice, is 2 keyframes); all of them
	// while the map has one or two keyframes.
	const int minObs = m_map.numKeyFrames() > 2 ? m_opts.keyFrameRefMinObservations : 1;
	const int refMatches = m_map.hasKeyFrame(m_refKf) ? m_map.keyframe(m_refKf).trackedLandmarks(minObs, &m_map) : 0;
	int trackedClose = 0, newClose = 0;
	for (std::size_t i = 0; i < cur.features.size(); i++)
	{
		const float d = cur.features.depth[i];
		if (d <= 0 || d > m_opts.closeDepth) continue;
		(cur.matches[i] != kNoLandmark ? trackedClose : newClose)++;
	}
	const bool needClose = trackedClose < m_opts.minTrackedClose && newClose > m_opts.minNewClose;
	const double ratio = m_map.numKeyFrames() < 2 ? kTrackedRatioWithOneKeyFrame : m_opts.keyFrameTrackedRatio;
	const bool timeout = sinceLast >= m_opts.maxFramesBetweenKeyFrames;
	const bool weak = cur.inliers < ratio * refMatches || needClose;
	return insertUnlessDeferred((timeout || weak) && cur.inliers > detail::kMinKeyFrameInliers, timeout, cur.inliers, refMatches);
}

KeyFrame Tracker::keyFrameOf(const Current& cur)
{
	KeyFrame kf;
	kf.frameIndex = cur.frame->index;
	kf.timestamp = cur.frame->timestamp;
	kf.T_world_cam = cur.T_world_cam;
	kf.features = cur.features;
	kf.depth = cur.frame->depth;
	kf.colour = (cur.frame->colour.empty() ? cur.frame->grey : cur.frame->colour).clone();
	return kf;
}

KeyFrameId Tracker::createKeyFrame(const Current& cur)
{
	KeyFrame kf = keyFrameOf(cur);
	kf.parent = m_refKf;
	kf.hasParent = m_map.hasKeyFrame(m_refKf);
	kf.mapId = kf.hasParent ? m_map.keyframe(m_refKf).mapId : m_newMapId;
	const KeyFrameId id = m_map.addKeyFrame(std::move(kf)).id;
	auto& k = m_map.keyframe(id);
	for (std::size_t i = 0; i < cur.matches.size(); i++)
		if (cur.matches[i] != kNoLandmark && m_map.hasLandmark(cur.matches[i]))
			m_map.addObservation(cur.matches[i], id, static_cast<int>(i));
	// New landmarks from depth: every close untracked keypoint, then farther ones until the
	// minimum count is reached (nearest first). None without depth (monocular): the
	// LocalMapper triangulates them.
	std::vector<std::pair<float, int>> byDepth;
	for (std::size_t i = 0; i < k.features.size(); i++)
		if (k.landmarks[i] == kNoLandmark && k.features.depth[i] > 0) byDepth.emplace_back(k.features.depth[i], static_cast<int>(i));
	std::sort(byDepth.begin(), byDepth.end());
	int created = 0;
	for (const auto& [d, i] : byDepth)
	{
		if (d > m_opts.closeDepth && created >= m_opts.minNewLandmarksPerKeyFrame) break;
		const Eigen::Vector3d p_cam = m_K.backProject(k.features.undistorted[i].x, k.features.undistorted[i].y, d);
		double x, y, z;
		k.T_world_cam.composePoint(p_cam.x(), p_cam.y(), p_cam.z(), x, y, z);
		m_map.addLandmark({x, y, z}, id, i);
		++created;
	}
	for (LandmarkId l : cur.matches)
		if (l != kNoLandmark && m_map.hasLandmark(l)) m_map.updateLandmarkStats(l);
	m_map.updateCovisibility(id);
	m_refKf = id;
	m_lastKfFrame = cur.frame->index;
	if (std::find(m_localKfs.begin(), m_localKfs.end(), id) == m_localKfs.end()) m_localKfs.insert(m_localKfs.begin(), id);
	return id;
}

}  // namespace keygrid::sfm
