#include <keygrid/loop/ConsistencyChecker.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace keygrid::loop
{
namespace
{
bool intersects(const std::set<KeyFrameId>& a, const std::set<KeyFrameId>& b)
{
	auto i = a.begin();
	auto j = b.begin();
	while (i != a.end() && j != b.end())
	{
		if (*i < *j) ++i;
		else if (*j < *i) ++j;
		else return true;
	}
	return false;
}
}  // namespace

ConsistencyChecker::ConsistencyChecker(int minConsecutive) : m_min(minConsecutive)
{
	if (minConsecutive < 1)
		throw std::invalid_argument("ConsistencyChecker: minConsecutive = " + std::to_string(minConsecutive) + " (must be >= 1)");
}

std::vector<KeyFrameId> ConsistencyChecker::check(const std::vector<CandidateGroup>& candidates)
{
	// A candidate group that overlaps (shares a keyframe with) a chain of the previous query
	// extends it by one; a group overlapping none starts a chain of length 1. Each previous chain
	// is carried over at most once, as in ORB-SLAM2, so a chain cannot fork; a candidate is
	// accepted when any chain it extends reaches minConsecutive queries.
	std::vector<Chain> next;
	std::vector<char> prevUsed(m_groups.size(), 0);
	std::vector<KeyFrameId> accepted;
	for (const auto& c : candidates)
	{
		std::set<KeyFrameId> g = c.group;
		g.insert(c.candidate);
		bool extended = false;
		bool acceptedThis = false;
		for (std::size_t p = 0; p < m_groups.size(); ++p)
		{
			if (!intersects(g, m_groups[p].group)) continue;
			const int len = m_groups[p].length + 1;
			if (!prevUsed[p])
			{
				prevUsed[p] = 1;
				next.push_back(Chain{g, len});
				extended = true;
			}
			if (len >= m_min && !acceptedThis)
			{
				accepted.push_back(c.candidate);
				acceptedThis = true;
			}
		}
		if (!extended) next.push_back(Chain{g, 1});
		if (m_min == 1 && !acceptedThis) accepted.push_back(c.candidate);
	}
	m_groups = std::move(next);
	return accepted;
}

}  // namespace keygrid::loop
