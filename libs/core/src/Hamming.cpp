#include <keygrid/core/Hamming.h>

namespace keygrid::core
{
namespace
{
void distancesPortable(const std::uint64_t* q, const std::uint64_t* rows, std::size_t stride, int n, int words, int* out)
{
	for (int r = 0; r < n; r++) out[r] = hammingDistance(q, rows + static_cast<std::size_t>(r) * stride, words);
}

#if (defined(__x86_64__) || defined(__i386__)) && !defined(__POPCNT__) && (defined(__GNUC__) || defined(__clang__))
#define KEYGRID_HAMMING_POPCNT_DISPATCH 1
/** The same loop compiled for CPUs with POPCNT: there __builtin_popcountll is one instruction. */
__attribute__((target("popcnt"))) void distancesPopcnt(
	const std::uint64_t* q, const std::uint64_t* rows, std::size_t stride, int n, int words, int* out)
{
	for (int r = 0; r < n; r++)
	{
		const std::uint64_t* row = rows + static_cast<std::size_t>(r) * stride;
		int d = 0;
		for (int w = 0; w < words; w++) d += __builtin_popcountll(q[w] ^ row[w]);
		out[r] = d;
	}
}
#endif
}  // namespace

void hammingDistances(const std::uint64_t* q, const std::uint64_t* rows, std::size_t strideWords, int n, int words, int* out)
{
#ifdef KEYGRID_HAMMING_POPCNT_DISPATCH
	static const bool popcnt = __builtin_cpu_supports("popcnt");
	if (popcnt) return distancesPopcnt(q, rows, strideWords, n, words, out);
#endif
	distancesPortable(q, rows, strideWords, n, words, out);
}
}  // namespace keygrid::core
