#pragma once
/** \file Grid3DParallel.h
 * Private helper of the 3D grid code: split [0, n) into contiguous chunks, one per thread.
 * Results stay deterministic as long as each chunk writes only its own outputs (or does
 * commutative operations) and per-thread partial results are combined in thread order.
 */
#include <algorithm>
#include <cstddef>
#include <thread>
#include <vector>

namespace keygrid::detail
{
/** Number of worker threads to use: `requested`, or the hardware concurrency when 0. */
inline unsigned resolveThreads(unsigned requested)
{
	if (requested > 0) return requested;
	const unsigned hw = std::thread::hardware_concurrency();
	return hw > 0 ? hw : 1;
}

/** Calls f(begin, end, threadIndex) on `threads` contiguous chunks of [0, n); chunk t is
 * handled by thread t (chunk 0 on the calling thread). Starts no more threads than there are
 * `grain`-sized pieces of work: starting a thread costs tens of microseconds. */
template <class F>
void parallelChunks(std::size_t n, unsigned threads, F&& f, std::size_t grain = 1)
{
	const std::size_t pieces = std::max<std::size_t>(1, n / std::max<std::size_t>(grain, 1));
	threads = std::max(1u, std::min<unsigned>(threads, static_cast<unsigned>(std::min<std::size_t>(pieces, 1024))));
	if (threads == 1)
	{
		f(std::size_t(0), n, 0u);
		return;
	}
	std::vector<std::thread> pool;
	pool.reserve(threads - 1);
	const std::size_t per = (n + threads - 1) / threads;
	for (unsigned t = 1; t < threads; ++t)
	{
		const std::size_t b = std::min(n, per * t), e = std::min(n, per * (t + 1));
		pool.emplace_back([&f, b, e, t]() { f(b, e, t); });
	}
	f(std::size_t(0), std::min(n, per), 0u);
	for (auto& th : pool) th.join();
}

}  // namespace keygrid::detail
