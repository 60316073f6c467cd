#include <keygrid/loop/KeyFrameDatabase.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace keygrid::loop
{
void KeyFrameDatabase::add(KeyFrameId id, const BowVector& v)
{
	erase(id);
	std::uint32_t slot;
	if (!m_freeSlots.empty())
	{
		slot = m_freeSlots.back();
		m_freeSlots.pop_back();
	}
	else
	{
		slot = static_cast<std::uint32_t>(m_idOf.size());
		m_idOf.push_back(0);
		m_vectors.emplace_back();
	}
	m_idOf[slot] = id;
	BowVector n = v;
	normaliseL1(n);
	for (const auto& e : n)
	{
		if (e.word >= m_index.size()) m_index.resize(static_cast<std::size_t>(e.word) + 1);
		m_index[e.word].push_back(Posting{slot, e.weight});
	}
	m_vectors[slot] = std::move(n);
	m_slotOf[id] = slot;
}

bool KeyFrameDatabase::erase(KeyFrameId id)
{
	const auto it = m_slotOf.find(id);
	if (it == m_slotOf.end()) return false;
	const std::uint32_t slot = it->second;
	for (const auto& e : m_vectors[slot])
	{
		auto& list = m_index[e.word];
		list.erase(std::remove_if(list.begin(), list.end(), [slot](const Posting& p) { return p.slot == slot; }), list.end());
	}
	m_vectors[slot].clear();
	m_freeSlots.push_back(slot);
	m_slotOf.erase(it);
	return true;
}

void KeyFrameDatabase::clear()
{
	m_index.clear();
	m_slotOf.clear();
	m_idOf.clear();
	m_vectors.clear();
	m_freeSlots.clear();
}

const BowVector& KeyFrameDatabase::bow(KeyFrameId id) const { return m_vectors[m_slotOf.at(id)]; }

std::vector<DatabaseCandidate> KeyFrameDatabase::query(const BowVector& v, const DatabaseQuery& q) const
{
	// Accumulate, over the postings of the query's words, the L1 score terms
	// 0.5 (|a| + |b| - |a - b|) (see l1Score) and the number of shared words per keyframe.
	const double norm = l1Norm(v);
	std::vector<DatabaseCandidate> out;
	if (norm <= 0 || m_slotOf.empty()) return out;
	m_scratchScore.assign(m_idOf.size(), 0.0);
	m_scratchCommon.assign(m_idOf.size(), 0);
	for (const auto& e : v)
	{
		if (e.word >= m_index.size()) continue;
		const double a = e.weight / norm;
		for (const auto& p : m_index[e.word])
		{
			m_scratchScore[p.slot] += std::abs(a) + std::abs(p.weight) - std::abs(a - p.weight);
			++m_scratchCommon[p.slot];
		}
	}
	std::uint32_t maxCommon = 0;
	for (const auto& [id, slot] : m_slotOf)
		if (!q.exclude.count(id)) maxCommon = std::max(maxCommon, m_scratchCommon[slot]);
	if (maxCommon == 0) return out;
	const double minCommon = q.minCommonWordsRatio * maxCommon;
	double minScore = q.minScore;
	if (q.referenceScore > 0) minScore = std::max(minScore, q.minRatioToReference * q.referenceScore);
	for (const auto& [id, slot] : m_slotOf)
	{
		const std::uint32_t common = m_scratchCommon[slot];
		if (common == 0 || common < minCommon || q.exclude.count(id)) continue;
		const double s = 0.5 * m_scratchScore[slot];
		if (s < minScore) continue;
		out.push_back(DatabaseCandidate{id, s, common});
	}
	std::sort(out.begin(), out.end(), [](const DatabaseCandidate& a, const DatabaseCandidate& b) {
		return a.score != b.score ? a.score > b.score : a.id < b.id;
	});
	if (q.maxResults > 0 && out.size() > q.maxResults) out.resize(q.maxResults);
	return out;
}

}  // namespace keygrid::loop
