#include <keygrid/core/TimestampAssociation.h>

#include <algorithm>
#include <cmath>

namespace keygrid::core
{
std::vector<std::pair<std::size_t, std::size_t>> associateTimestamps(
	const std::vector<double>& a, const std::vector<double>& b, double maxDt)
{
	// Candidate pairs within maxDt, found with a binary search on b sorted by time.
	std::vector<std::size_t> ib(b.size());
	for (std::size_t i = 0; i < ib.size(); i++) ib[i] = i;
	std::sort(ib.begin(), ib.end(), [&](auto x, auto y) { return b[x] < b[y]; });
	struct Cand
	{
		double dt;
		std::size_t i, j;
	};
	std::vector<Cand> cands;
	for (std::size_t i = 0; i < a.size(); i++)
	{
		auto lo = std::lower_bound(
			ib.begin(), ib.end(), a[i] - maxDt, [&](std::size_t j, double t) { return b[j] < t; });
		for (auto it = lo; it != ib.end() && b[*it] <= a[i] + maxDt; ++it)
			cands.push_back({std::abs(a[i] - b[*it]), i, *it});
	}
	std::stable_sort(
		cands.begin(), cands.end(), [](const Cand& x, const Cand& y) { return x.dt < y.dt; });
	std::vector<char> usedA(a.size(), 0), usedB(b.size(), 0);
	std::vector<std::pair<std::size_t, std::size_t>> out;
	for (const auto& c : cands)
		if (!usedA[c.i] && !usedB[c.j])
		{
			usedA[c.i] = usedB[c.j] = 1;
			out.emplace_back(c.i, c.j);
		}
	std::sort(out.begin(), out.end(), [&](auto& x, auto& y) { return a[x.first] < a[y.first]; });
	return out;
}

}  // namespace keygrid::core
