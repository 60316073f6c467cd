#include <keygrid/loop/BowVector.h>

#include <algorithm>
#include <cmath>

namespace keygrid::loop
{
void canonicalise(BowVector& v)
{
	std::sort(v.begin(), v.end(), [](const BowEntry& a, const BowEntry& b) { return a.word < b.word; });
	std::size_t out = 0;
	for (std::size_t i = 0; i < v.size(); ++i)
	{
		if (out > 0 && v[out - 1].word == v[i].word) v[out - 1].weight += v[i].weight;
		else v[out++] = v[i];
	}
	v.resize(out);
}

double l1Norm(const BowVector& v)
{
	double n = 0;
	for (const auto& e : v) n += std::abs(e.weight);
	return n;
}

void normaliseL1(BowVector& v)
{
	const double n = l1Norm(v);
	if (n <= 0) return;
	for (auto& e : v) e.weight /= n;
}

double l1Score(const BowVector& v1, const BowVector& v2)
{
	const double n1 = l1Norm(v1), n2 = l1Norm(v2);
	if (n1 <= 0 || n2 <= 0) return 0.0;
	double s = 0;
	auto a = v1.begin();
	auto b = v2.begin();
	while (a != v1.end() && b != v2.end())
	{
		if (a->word < b->word) ++a;
		else if (b->word < a->word) ++b;
		else
		{
			const double wa = a->weight / n1, wb = b->weight / n2;
			s += std::abs(wa) + std::abs(wb) - std::abs(wa - wb);
			++a;
			++b;
		}
	}
	return 0.5 * s;
}

}  // namespace keygrid::loop
