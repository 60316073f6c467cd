/** \file Tracker_monocular.cpp
 * The Tracker's monocular mode: the map start from two views and the keyframe rule of a camera
 * without depth (see Tracker.h). Tracking itself is the RGB-D mode's: observations without
 * depth take the reprojection cost's two-residual form.
 */
#include <keygrid/sfm/InitialMatcher.h>
#include <keygrid/sfm/LocalBundleAdjuster.h>
#include <keygrid/sfm/Tracker.h>

#include "detail/TrackerConstants.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace keygrid::sfm
{
namespace
{
/** T_cur_ref of a two-view motion (X_cur = R X_ref + t). */
mrpt::poses::CPose3D poseOf(const RelativeMotion& m)
{
	mrpt::math::CMatrixDouble33 R;
	mrpt::math::CVectorFixedDouble<3> t;
	for (int i = 0; i < 3; i++)
	{
		for (int j = 0; j < 3; j++) R(i, j) = m.R_cur_ref(i, j);
		t[i] = m.t_cur_ref(i);
	}
	return mrpt::poses::CPose3D::FromRotationAndTranslation(R, t);
}

std::string frameText(std::size_t index) { return "frame " + std::to_string(index); }
}  // namespace

void Tracker::setMonocularReference(const Current& cur)
{
	MonocularReference ref;
	ref.index = cur.frame->index;
	ref.timestamp = cur.frame->timestamp;
	// A copy: the source may reuse its image buffers for the following frames.
	ref.colour = (cur.frame->colour.empty() ? cur.frame->grey : cur.frame->colour).clone();
	ref.features = cur.features;
	ref.predicted = cur.features.undistorted;
	m_monoRef = std::move(ref);
}

bool Tracker::initializeMonocular(Current& cur, TrackedFrame& out)
{
	const auto& mo = m_opts.mono;
	const int keypoints = static_cast<int>(cur.features.size());
	if (keypoints <= mo.initMinKeypoints)
	{
		m_monoRef.reset();
		out.initMessage = frameText(cur.frame->index) + ": " + std::to_string(keypoints) + " keypoints, a reference frame needs more than " +
						  std::to_string(mo.initMinKeypoints);
		return false;
	}
	if (!m_monoRef)
	{
		setMonocularReference(cur);
		out.initNewReference = true;
		out.initMessage = frameText(cur.frame->index) + ": reference frame of the map start (" + std::to_string(keypoints) + " keypoints)";
		return false;
	}
	auto& ref = *m_monoRef;
	InitialMatchOptions io;
	io.windowPx = mo.initWindowPx;
	io.maxDistance = cur.features.isBinary() ? mo.initMaxDistanceOrb : mo.initMaxDistanceSift;
	io.ratio = mo.initRatio;
	io.checkOrientation = mo.initCheckOrientation;
	std::vector<int> refToCur;
	const int n = searchForInitialization(ref.features, cur.features, ref.predicted, io, refToCur);
	const std::string head = frameText(cur.frame->index) + " with reference " + frameText(ref.index) + ": ";
	if (n < mo.twoView.minMatches)
	{
		// The view has moved away from the reference: start again from this frame.
		out.initMessage = head + std::to_string(n) + " matches (" + std::to_string(mo.twoView.minMatches) + " needed); new reference";
		setMonocularReference(cur);
		out.initNewReference = true;
		return false;
	}
	TwoViewMatches m;
	std::vector<std::pair<int, int>> pairs;
	for (std::size_t i = 0; i < refToCur.size(); i++)
	{
		const int j = refToCur[i];
		if (j < 0) continue;
		pairs.emplace_back(static_cast<int>(i), j);
		m.px_ref.emplace_back(ref.features.undistorted[i].x, ref.features.undistorted[i].y);
		m.px_cur.emplace_back(cur.features.undistorted[j].x, cur.features.undistorted[j].y);
		m.scale_ref.push_back(ref.features.levelScale[ref.features.keypoints[i].octave]);
		m.scale_cur.push_back(cur.features.levelScale[cur.features.keypoints[j].octave]);
	}
	TwoViewResult r = TwoViewInitializer(m_K, mo.twoView).initialize(m);
	const auto resolved = resolvePlaneAmbiguity(r);
	if (resolved)
	{
		const auto j = resolved;
		// The motion whose plane the first ambiguous frame saw too: its points become the map.
		const auto& c = r.candidates[*j];
		r.ok = true;
		r.motion = c.motion;
		r.points_ref = c.points_ref;
		r.triangulated = c.triangulated;
		r.inliers = c.triangulated;
		r.numInliers = static_cast<int>(std::count(c.triangulated.begin(), c.triangulated.end(), uint8_t{1}));
		r.parallaxDeg = c.parallaxDeg;
	}
	if (r.ok && startMonocularMap(cur, r, pairs, out))
	{
		if (resolved) out.initMessage += "; the plane of the first ambiguous frame picked the motion";
		return true;
	}
	if (!r.ok) out.initMessage = head + std::to_string(n) + " matches, " + r.message;
	if (static_cast<int>(cur.frame->index - ref.index) >= mo.initMaxFrames)
	{
		out.initMessage += "; new reference after " + std::to_string(mo.initMaxFrames) + " frames";
		setMonocularReference(cur);
		out.initNewReference = true;
	}
	return false;
}

std::optional<std::size_t> Tracker::resolvePlaneAmbiguity(const TwoViewResult& r)
{
	const double tol = m_opts.mono.initPlaneNormalDeg * M_PI / 180.0;
	if (!(tol > 0) || r.failure != TwoViewFailure::Ambiguous || r.model != TwoViewModel::Homography || r.candidates.size() < 2)
		return std::nullopt;
	auto& first = m_monoRef->ambiguousNormals;
	if (first.empty())
	{
		for (const auto& c : r.candidates) first.push_back(c.planeNormal_ref);
		return std::nullopt;
	}
	// Angle of each candidate's plane to the nearest plane of the first ambiguous result.
	std::vector<double> angle;
	for (const auto& c : r.candidates)
	{
		double best = M_PI;
		for (const auto& n : first) best = std::min(best, std::acos(std::clamp(c.planeNormal_ref.dot(n), -1.0, 1.0)));
		angle.push_back(best);
	}
	const auto j = static_cast<std::size_t>(std::min_element(angle.begin(), angle.end()) - angle.begin());
	const auto& tri = r.candidates[j].triangulated;
	if (!(angle[j] < tol) || std::count(tri.begin(), tri.end(), uint8_t{1}) < m_opts.mono.twoView.minTriangulated) return std::nullopt;
	for (std::size_t k = 0; k < angle.size(); k++)
		if (k != j && !(angle[k] > 2 * tol)) return std::nullopt;
	return j;
}

bool Tracker::startMonocularMap(Current& cur, const TwoViewResult& r, const std::vector<std::pair<int, int>>& pairs, TrackedFrame& out)
{
	const auto& mo = m_opts.mono;
	auto& ref = *m_monoRef;
	// The reference camera defines the world frame, as the first keyframe of an RGB-D map.
	KeyFrame first;
	first.frameIndex = ref.index;
	first.timestamp = ref.timestamp;
	first.features = ref.features;
	first.colour = ref.colour;
	first.mapId = m_newMapId;
	const KeyFrameId id1 = m_map.addKeyFrame(std::move(first)).id;
	cur.T_world_cam = -poseOf(r.motion);
	KeyFrame second = keyFrameOf(cur);
	second.parent = id1;
	second.hasParent = true;
	second.mapId = m_newMapId;
	const KeyFrameId id2 = m_map.addKeyFrame(std::move(second)).id;
	std::vector<LandmarkId> created;
	for (std::size_t k = 0; k < pairs.size(); k++)
	{
		if (!r.inliers[k] || !r.triangulated[k]) continue;
		const LandmarkId l = m_map.addLandmark(r.points_ref[k], id1, pairs[k].first);
		m_map.addObservation(l, id2, pairs[k].second);
		created.push_back(l);
	}
	for (LandmarkId l : created) m_map.updateLandmarkStats(l);
	m_map.updateCovisibility(id1);
	m_map.updateCovisibility(id2);

	// Both keyframes and the points refined together, the reference fixed (the gauge of
	// rotation and translation; the scale is set below).
	BundleAdjusterOptions ba = mo.ba;
	ba.iterations = mo.initBaIterations;
	bundleAdjust(m_map, {id2}, {id1}, m_K, ba);

	// Scale: median depth of the first keyframe's points 1 (ORB-SLAM), so that thresholds in
	// map units see a scene of the same size whatever the baseline of the start was.
	std::vector<double> depths;
	for (LandmarkId l : m_map.keyframe(id1).landmarks)
		if (l != kNoLandmark && m_map.hasLandmark(l)) depths.push_back(m_map.landmark(l).p_world.z());
	std::size_t mid = depths.size() / 2;
	std::nth_element(depths.begin(), depths.begin() + static_cast<std::ptrdiff_t>(mid), depths.end());
	const double median = depths.empty() ? 0.0 : depths[mid];
	if (static_cast<int>(depths.size()) < mo.initMinLandmarks || !(median > 0))
	{
		char text[200];
		std::snprintf(
			text, sizeof(text), "%s with reference %s: two-view map kept %zu landmarks after bundle adjustment (%d needed)",
			frameText(cur.frame->index).c_str(), frameText(ref.index).c_str(), depths.size(), mo.initMinLandmarks);
		out.initMessage = text;
		m_map.eraseKeyFrame(id2);
		m_map.eraseKeyFrame(id1);
		return false;
	}
	const double s = 1.0 / median;
	auto& kf2 = m_map.keyframe(id2);
	scaleTranslation(kf2.T_world_cam, s);
	for (LandmarkId l : m_map.keyframe(id1).landmarks)
		if (l != kNoLandmark && m_map.hasLandmark(l))
		{
			m_map.landmark(l).p_world *= s;
			m_map.updateLandmarkStats(l);
		}
	for (LandmarkId l : kf2.landmarks)
		if (l != kNoLandmark && m_map.hasLandmark(l) && !m_map.landmark(l).observations.count(id1))
		{
			m_map.landmark(l).p_world *= s;
			m_map.updateLandmarkStats(l);
		}
	if (m_hoc)
	{
		m_hoc->confirmInitialMap(m_map, id1);
		m_hoc->confirmInitialMap(m_map, id2);
	}

	char text[240];
	std::snprintf(
		text, sizeof(text), "%s with reference %s: map started (%s, %d inliers, %d landmarks, parallax %.2f deg)",
		frameText(cur.frame->index).c_str(), frameText(ref.index).c_str(), toString(r.model), r.numInliers,
		static_cast<int>(depths.size()), r.parallaxDeg);
	out.initMessage = text;
	cur.T_world_cam = kf2.T_world_cam;
	startTrackingOnNewMap(cur, out, {id2, id1}, static_cast<int>(depths.size()));
	out.hasInitialKeyFrame = true;
	out.initialKeyFrame = id1;
	out.initialFrameIndex = ref.index;
	m_monoRef.reset();
	return true;
}

void Tracker::scaleMotion(double s)
{
	if (m_velocity) scaleTranslation(*m_velocity, s);
	if (m_lastRelative) scaleTranslation(m_lastRelative->second, s);
}

void Tracker::onMapRescaled(double s)
{
	scaleTranslation(m_lastPose, s);
	scaleMotion(s);
}

void Tracker::onMapRescaledLocally(double s)
{
	scaleMotion(s);
	onMapCorrected();
}

Tracker::KeyFrameNeed Tracker::needKeyFrameMonocular(const Current& cur) const
{
	const auto& mo = m_opts.mono;
	const int sinceLast = static_cast<int>(cur.frame->index - m_lastKfFrame);
	const int minObs = m_map.numKeyFrames() > 2 ? mo.keyFrameRefMinObservations : 2;
	const int refMatches = m_map.hasKeyFrame(m_refKf) ? m_map.keyframe(m_refKf).trackedLandmarks(minObs, &m_map) : 0;
	const bool timeout = sinceLast >= m_opts.maxFramesBetweenKeyFrames;
	const bool weak = cur.inliers < mo.keyFrameTrackedRatio * refMatches;
	return insertUnlessDeferred((timeout || weak) && cur.inliers > detail::kMinKeyFrameInliers, timeout, cur.inliers, refMatches);
}

}  // namespace keygrid::sfm
