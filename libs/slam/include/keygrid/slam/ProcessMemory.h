#pragma once
/** \file ProcessMemory.h
 * Memory of the running process, for report.json: the resident set now and at its peak, and
 * RSS samples taken as the map grows so that the growth per keyframe can be computed from a
 * run (tests/benchmarks/slam/office_loop_memory.sh).
 */
#include <cstddef>
#include <string>
#include <vector>

namespace keygrid::slam
{
/** Resident set size of this process now [MB] (/proc/self/statm; 0 where unavailable). */
double residentMegabytes();
/** Largest resident set size of this process so far [MB] (getrusage ru_maxrss). */
double peakResidentMegabytes();

/** RSS samples taken when the keyframe count first reaches each multiple of `every`. */
class MemorySampler
{
   public:
	struct Sample
	{
		std::size_t keyframes{0}, frames{0};
		double rssMb{0};
	};

	/** `every`: keyframes between two samples (>= 1). */
	explicit MemorySampler(std::size_t every = 25);

	/** After a frame: samples residentMegabytes() when `keyframes` reached the next multiple
	 * of `every` (a count that drops, e.g. by keyframe culling, and rises again to a multiple
	 * already sampled takes no second sample). */
	void onFrame(std::size_t keyframes, std::size_t frames);
	/** The same with a given RSS [MB] (what onFrame reads; tests pass their own). */
	void onFrame(std::size_t keyframes, std::size_t frames, double rssMb);

	const std::vector<Sample>& samples() const { return m_samples; }
	/** JSON array of [keyframes, frames, rss_mb] triples. */
	std::string toJson() const;

   private:
	std::size_t m_every;
	std::size_t m_next;  //!< the keyframe count of the next sample
	std::vector<Sample> m_samples;
};

}  // namespace keygrid::slam
