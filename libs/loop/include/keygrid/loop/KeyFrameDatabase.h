#pragma once
/** \file KeyFrameDatabase.h
 * Inverted index word -> (keyframe, weight) for place recognition: a query scores only the
 * keyframes that share at least one word with it, with the exact L1 score of BowVector.h.
 */
#include <keygrid/loop/BowVector.h>

#include <cstddef>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

namespace keygrid::loop
{
struct DatabaseQuery
{
	/** Candidates returned at most, best first; 0 = all (Default: 10) */
	std::size_t maxResults{10};
	/** Candidates scoring below this absolute L1 score are dropped (Default: 0) */
	double minScore{0.0};
	/** ORB-SLAM-style normalisation: when > 0, candidates need
	 * score >= minRatioToReference * referenceScore, where the caller passes as reference the
	 * lowest score between the query keyframe and its covisible keyframes (Default: 0 = off) */
	double referenceScore{0.0};
	/** Factor on referenceScore (Default: 1.0, ORB-SLAM2 uses the min covisible score itself) */
	double minRatioToReference{1.0};
	/** Candidates must share at least this fraction of the best candidate's common-word count
	 * (ORB-SLAM2 uses 0.8) (Default: 0.8) */
	double minCommonWordsRatio{0.8};
	/** Keyframes never returned (the query itself, its covisible neighbours) */
	std::set<KeyFrameId> exclude;
};

struct DatabaseCandidate
{
	KeyFrameId id{0};
	double score{0};         //!< L1 score with the query, in [0, 1]
	std::size_t commonWords{0};  //!< words shared with the query
};

class KeyFrameDatabase
{
   public:
	/** Adds (or replaces) a keyframe. The vector must be canonical (Vocabulary::transform). */
	void add(KeyFrameId id, const BowVector& v);
	/** Removes a keyframe; returns false when it was not there. */
	bool erase(KeyFrameId id);
	bool contains(KeyFrameId id) const { return m_slotOf.count(id) > 0; }
	std::size_t size() const { return m_slotOf.size(); }
	void clear();

	/** Keyframes sharing words with `v`, ranked by score (ties: lower id first). Uses internal
	 * scratch buffers: do not call concurrently on the same database. */
	std::vector<DatabaseCandidate> query(const BowVector& v, const DatabaseQuery& q = {}) const;

	/** Stored vector of a keyframe (throws std::out_of_range when absent). */
	const BowVector& bow(KeyFrameId id) const;

   private:
	struct Posting
	{
		std::uint32_t slot;
		double weight;  //!< L1-normalised weight of the word in that keyframe
	};
	std::vector<std::vector<Posting>> m_index;  //!< word -> postings
	std::unordered_map<KeyFrameId, std::uint32_t> m_slotOf;
	std::vector<KeyFrameId> m_idOf;      //!< slot -> keyframe id
	std::vector<BowVector> m_vectors;    //!< slot -> normalised vector
	std::vector<std::uint32_t> m_freeSlots;
	mutable std::vector<double> m_scratchScore;
	mutable std::vector<std::uint32_t> m_scratchCommon;
};

}  // namespace keygrid::loop
