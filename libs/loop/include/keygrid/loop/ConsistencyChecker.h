#pragma once
/** \file ConsistencyChecker.h
 * Temporal (group) consistency of loop candidates, as in ORB-SLAM's loop detection: a candidate
 * is only accepted once candidates of overlapping covisibility groups have been found for
 * `minConsecutive` consecutive keyframe queries. A single spurious BoW match rarely repeats
 * over several keyframes; a real revisit does.
 */
#include <keygrid/loop/BowVector.h>

#include <set>
#include <vector>

namespace keygrid::loop
{
/** A candidate keyframe and its group: the candidate plus its covisible keyframes. */
struct CandidateGroup
{
	KeyFrameId candidate{0};
	std::set<KeyFrameId> group;
};

class ConsistencyChecker
{
   public:
	/** minConsecutive: consecutive queries needed (ORB-SLAM2 uses 3); >= 1. */
	explicit ConsistencyChecker(int minConsecutive = 3);

	/** Feeds the candidates found for the next query keyframe (in query order). Returns the
	 * candidates whose group chain has reached minConsecutive queries, ordered as given. An
	 * empty input breaks every chain. */
	std::vector<KeyFrameId> check(const std::vector<CandidateGroup>& candidates);

	/** Forgets all chains (e.g. after a loop was closed). */
	void reset() { m_groups.clear(); }

	int minConsecutive() const { return m_min; }
	/** Groups carried over from the last query with their chain lengths. */
	std::size_t activeGroups() const { return m_groups.size(); }

   private:
	struct Chain
	{
		std::set<KeyFrameId> group;
		int length{0};
	};
	int m_min;
	std::vector<Chain> m_groups;
};

}  // namespace keygrid::loop
