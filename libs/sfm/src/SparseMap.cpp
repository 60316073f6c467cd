#include <keygrid/sfm/SparseMap.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

namespace keygrid::sfm
{
Eigen::Vector3d KeyFrame::cameraCenter() const { return translationOf(T_world_cam); }

int KeyFrame::trackedLandmarks(int minObservations, const SparseMap* map) const
{
	int n = 0;
	for (LandmarkId id : landmarks)
	{
		if (id == kNoLandmark) continue;
		if (map && minObservations > 1)
		{
			if (!map->hasLandmark(id) ||
				static_cast<int>(map->landmark(id).observations.size()) < minObservations)
				continue;
		}
		++n;
	}
	return n;
}

KeyFrame& SparseMap::addKeyFrame(KeyFrame kf)
{
	kf.id = m_nextKf++;
	kf.landmarks.resize(kf.features.size(), kNoLandmark);
	return m_keyframes.emplace(kf.id, std::move(kf)).first->second;
}

KeyFrame& SparseMap::restoreKeyFrame(KeyFrame kf)
{
	if (m_keyframes.count(kf.id)) throw std::invalid_argument("SparseMap::restoreKeyFrame: keyframe " + std::to_string(kf.id) + " is in the map already");
	kf.landmarks.assign(kf.features.size(), kNoLandmark);
	kf.covisibility.clear();
	m_nextKf = std::max(m_nextKf, kf.id + 1);
	const KeyFrameId id = kf.id;
	return m_keyframes.emplace(id, std::move(kf)).first->second;
}

void SparseMap::restoreLandmark(Landmark lm)
{
	if (m_landmarks.count(lm.id)) throw std::invalid_argument("SparseMap::restoreLandmark: landmark " + std::to_string(lm.id) + " is in the map already");
	for (const auto& [kfId, kp] : lm.observations)
	{
		const auto it = m_keyframes.find(kfId);
		if (it == m_keyframes.end() || kp < 0 || static_cast<std::size_t>(kp) >= it->second.landmarks.size())
			throw std::invalid_argument("SparseMap::restoreLandmark: landmark " + std::to_string(lm.id) + " is observed by keypoint " +
										std::to_string(kp) + " of keyframe " + std::to_string(kfId) + ", which the map does not hold");
	}
	for (const auto& [kfId, kp] : lm.observations) m_keyframes.at(kfId).landmarks[static_cast<std::size_t>(kp)] = lm.id;
	m_nextLm = std::max(m_nextLm, lm.id + 1);
	const LandmarkId id = lm.id;
	m_landmarks.emplace(id, std::move(lm));
}

LandmarkId SparseMap::addLandmark(const Eigen::Vector3d& p, KeyFrameId kf, int kp)
{
	Landmark lm;
	lm.id = m_nextLm++;
	lm.p_world = p;
	lm.firstKeyFrame = kf;
	lm.descriptor = m_keyframes.at(kf).features.descriptors.row(kp).clone();
	const LandmarkId id = lm.id;
	m_landmarks.emplace(id, std::move(lm));
	addObservation(id, kf, kp);
	updateLandmarkStats(id);
	return id;
}

void SparseMap::addObservation(LandmarkId lm, KeyFrameId kf, int kp)
{
	auto& k = m_keyframes.at(kf);
	if (kp < 0 || static_cast<std::size_t>(kp) >= k.landmarks.size())
		throw std::out_of_range("addObservation: keypoint " + std::to_string(kp) + " out of range");
	auto& l = m_landmarks.at(lm);
	if (auto it = l.observations.find(kf); it != l.observations.end()) k.landmarks[it->second] = kNoLandmark;
	l.observations[kf] = kp;
	k.landmarks[kp] = lm;
}

void SparseMap::eraseObservation(LandmarkId lm, KeyFrameId kf)
{
	auto it = m_landmarks.find(lm);
	if (it == m_landmarks.end()) return;
	auto o = it->second.observations.find(kf);
	if (o == it->second.observations.end()) return;
	if (auto k = m_keyframes.find(kf); k != m_keyframes.end() && k->second.landmarks[o->second] == lm)
		k->second.landmarks[o->second] = kNoLandmark;
	it->second.observations.erase(o);
	if (it->second.observations.empty()) m_landmarks.erase(it);
}

void SparseMap::eraseLandmark(LandmarkId lm)
{
	auto it = m_landmarks.find(lm);
	if (it == m_landmarks.end()) return;
	for (const auto& [kf, kp] : it->second.observations)
		if (auto k = m_keyframes.find(kf); k != m_keyframes.end() && k->second.landmarks[kp] == lm)
			k->second.landmarks[kp] = kNoLandmark;
	m_landmarks.erase(it);
}

void SparseMap::rescale(double s)
{
	if (!(std::isfinite(s) && s > 0)) throw std::invalid_argument("SparseMap::rescale: s = " + std::to_string(s) + " (must be finite and > 0)");
	for (auto& [id, kf] : m_keyframes) scaleTranslation(kf.T_world_cam, s);
	for (auto& [id, lm] : m_landmarks)
	{
		lm.p_world *= s;
		lm.minDistance *= s;
		lm.maxDistance *= s;
	}
	for (auto& [id, e] : m_erased) scaleTranslation(e.second, s);
}

void SparseMap::eraseKeyFrame(KeyFrameId id)
{
	auto it = m_keyframes.find(id);
	if (it == m_keyframes.end()) return;
	for (LandmarkId lm : std::vector<LandmarkId>(it->second.landmarks))
		if (lm != kNoLandmark) eraseObservation(lm, id);
	for (const auto& [other, w] : it->second.covisibility)
		if (auto o = m_keyframes.find(other); o != m_keyframes.end()) o->second.covisibility.erase(id);
	if (it->second.hasParent && m_keyframes.count(it->second.parent))
		m_erased[id] = {it->second.parent, it->second.T_world_cam - m_keyframes.at(it->second.parent).T_world_cam};
	// Children of the removed keyframe adopt its parent.
	for (auto& [kid, kf] : m_keyframes)
		if (kf.hasParent && kf.parent == id)
		{
			kf.parent = it->second.parent;
			kf.hasParent = it->second.hasParent;
		}
	m_keyframes.erase(it);
}

bool SparseMap::poseOf(KeyFrameId id, mrpt::poses::CPose3D& T) const
{
	mrpt::poses::CPose3D T_acc;  // T_ancestor_kf accumulated along erased links
	for (int hops = 0; hops < 100000; hops++)
	{
		if (auto it = m_keyframes.find(id); it != m_keyframes.end())
		{
			T = it->second.T_world_cam + T_acc;
			return true;
		}
		auto e = m_erased.find(id);
		if (e == m_erased.end()) return false;
		T_acc = e->second.second + T_acc;
		id = e->second.first;
	}
	return false;
}

void SparseMap::replaceLandmark(LandmarkId gone, LandmarkId keep)
{
	if (gone == keep || !hasLandmark(gone) || !hasLandmark(keep)) return;
	const auto obs = m_landmarks.at(gone).observations;
	auto& k = m_landmarks.at(keep);
	for (const auto& [kf, kp] : obs)
	{
		if (k.observations.count(kf)) continue;  // keep's own observation in that keyframe wins
		k.observations[kf] = kp;
		m_keyframes.at(kf).landmarks[kp] = keep;
	}
	k.visibleCount += m_landmarks.at(gone).visibleCount;
	k.foundCount += m_landmarks.at(gone).foundCount;
	// Remaining links of `gone` (keyframes where keep already had an observation) are dropped.
	for (const auto& [kf, kp] : obs)
		if (m_keyframes.at(kf).landmarks[kp] == gone) m_keyframes.at(kf).landmarks[kp] = kNoLandmark;
	m_landmarks.erase(gone);
	m_replacedBy[gone] = keep;
	updateLandmarkStats(keep);
}

LandmarkId SparseMap::resolve(LandmarkId id) const
{
	// Each fusion maps an existing landmark onto another existing one, so the chain ends.
	for (auto r = m_replacedBy.find(id); r != m_replacedBy.end(); r = m_replacedBy.find(id)) id = r->second;
	return hasLandmark(id) ? id : kNoLandmark;
}

std::vector<const Landmark*> SparseMap::resolvedLandmarks() const
{
	// A restored map may hold fused ids above every landmark's.
	const LandmarkId size = m_replacedBy.empty() ? m_nextLm : std::max(m_nextLm, m_replacedBy.rbegin()->first + 1);
	std::vector<const Landmark*> table(static_cast<std::size_t>(size), nullptr);
	for (const auto& [id, lm] : m_landmarks) table[static_cast<std::size_t>(id)] = &lm;
	for (const auto& [gone, keep] : m_replacedBy) table[static_cast<std::size_t>(gone)] = findLandmark(resolve(gone));
	return table;
}

void SparseMap::updateLandmarkStats(LandmarkId id)
{
	auto& l = m_landmarks.at(id);
	if (l.observations.empty()) return;
	Eigen::Vector3d n = Eigen::Vector3d::Zero();
	std::vector<cv::Mat> descs;
	for (const auto& [kf, kp] : l.observations)
	{
		const auto& k = m_keyframes.at(kf);
		n += (l.p_world - k.cameraCenter()).normalized();
		descs.push_back(k.features.descriptors.row(kp));
	}
	l.normal = n.normalized();
	// Scale-invariance distance range from the reference (first) observation.
	const auto ref = l.observations.count(l.firstKeyFrame) ? l.observations.find(l.firstKeyFrame) : l.observations.begin();
	const auto& rk = m_keyframes.at(ref->first);
	const double dist = (l.p_world - rk.cameraCenter()).norm();
	const int level = rk.features.keypoints[ref->second].octave;
	const auto& ls = rk.features.levelScale;
	const double levelFactor = ls.empty() ? 1.0 : ls[std::min<std::size_t>(level, ls.size() - 1)];
	const std::size_t top = static_cast<std::size_t>(std::max(0, rk.features.numLevels - 1));
	const double maxLevelFactor = ls.empty() ? 1.0 : ls[std::min<std::size_t>(top, ls.size() - 1)];
	l.maxDistance = dist * levelFactor;
	l.minDistance = l.maxDistance / maxLevelFactor;
	// Representative descriptor: least median distance to the others.
	if (descs.size() > 2)
	{
		std::size_t best = 0;
		float bestMedian = 1e30f;
		for (std::size_t i = 0; i < descs.size(); i++)
		{
			std::vector<float> d;
			for (std::size_t j = 0; j < descs.size(); j++)
				if (i != j) d.push_back(descriptorDistance(descs[i], descs[j]));
			std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
			if (d[d.size() / 2] < bestMedian)
			{
				bestMedian = d[d.size() / 2];
				best = i;
			}
		}
		l.descriptor = descs[best].clone();
	}
}

void SparseMap::updateCovisibility(KeyFrameId id, int minShared)
{
	auto& kf = m_keyframes.at(id);
	std::map<KeyFrameId, int> counts;
	for (LandmarkId lm : kf.landmarks)
	{
		if (lm == kNoLandmark) continue;
		auto it = m_landmarks.find(lm);
		if (it == m_landmarks.end()) continue;
		for (const auto& [other, kp] : it->second.observations)
			if (other != id) counts[other]++;
	}
	for (const auto& [other, w] : kf.covisibility)
		if (auto o = m_keyframes.find(other); o != m_keyframes.end()) o->second.covisibility.erase(id);
	kf.covisibility.clear();
	KeyFrameId bestId = 0;
	int bestW = 0;
	for (const auto& [other, w] : counts)
	{
		if (w > bestW)
		{
			bestW = w;
			bestId = other;
		}
		if (w < minShared) continue;
		kf.covisibility[other] = w;
		m_keyframes.at(other).covisibility[id] = w;
	}
	// Keep the graph connected: always link the strongest neighbour.
	if (bestW > 0 && !kf.covisibility.count(bestId))
	{
		kf.covisibility[bestId] = bestW;
		m_keyframes.at(bestId).covisibility[id] = bestW;
	}
}

std::vector<KeyFrameId> SparseMap::bestCovisibles(KeyFrameId id, std::size_t n) const
{
	std::vector<std::pair<int, KeyFrameId>> v;
	for (const auto& [other, w] : m_keyframes.at(id).covisibility) v.emplace_back(w, other);
	std::sort(v.begin(), v.end(), [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
	std::vector<KeyFrameId> out;
	for (std::size_t i = 0; i < v.size() && i < n; i++) out.push_back(v[i].second);
	return out;
}

double largestParallaxCos(const SparseMap& map, const Landmark& lm)
{
	double minCos = 1.0;
	std::optional<Eigen::Vector3d> first;
	for (const auto& [kf, idx] : lm.observations)
	{
		if (!map.hasKeyFrame(kf)) continue;
		const Eigen::Vector3d ray = (lm.p_world - translationOf(map.keyframe(kf).T_world_cam)).normalized();
		if (!first)
			first = ray;
		else
			minCos = std::min(minCos, first->dot(ray));
	}
	return minCos;
}

}  // namespace keygrid::sfm
