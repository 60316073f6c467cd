#include "Parallel.h"

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace keygrid::sim
{
void parallelRows(int rows, unsigned threads, const std::function<void(int, int)>& f)
{
	if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
	constexpr int kChunk = 8;  // rows per work item: small enough to balance uneven rows
	if (threads == 1 || rows <= kChunk)
	{
		f(0, rows);
		return;
	}
	std::atomic<int> nextRow{0};
	auto worker = [&] {
		for (;;)
		{
			const int r0 = nextRow.fetch_add(kChunk);
			if (r0 >= rows) return;
			f(r0, std::min(rows, r0 + kChunk));
		}
	};
	std::vector<std::thread> pool;
	for (unsigned i = 1; i < threads; i++) pool.emplace_back(worker);
	worker();
	for (auto& t : pool) t.join();
}

}  // namespace keygrid::sim
