#pragma once
/** \file StageTimings.h
 * Per-stage durations of the pipeline (load, extract, track, mapping, ...), summarised as
 * median and 95th percentile for report.json. Thread-safe: in threaded mode tracking, mapping
 * and loop closing add their samples from their own threads.
 */
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace keygrid::slam
{
class StageTimings
{
   public:
	void add(const std::string& stage, double seconds)
	{
		std::lock_guard<std::mutex> lk(m_mutex);
		m_samples[stage].push_back(seconds);
	}

	struct Summary
	{
		std::size_t count{0};
		double total{0}, mean{0}, median{0}, p95{0}, max{0};  //!< seconds
	};
	Summary summary(const std::string& stage) const;
	std::vector<std::string> stages() const;
	/** Mean of each run of `block` consecutive samples of a stage, in the order they were
	 * added [s] (a last, shorter run included): how a per-frame cost evolves along a run. */
	std::vector<double> blockMeans(const std::string& stage, std::size_t block) const;
	/** JSON object: {"stage": {"count":..,"median_ms":..,"p95_ms":..,"mean_ms":..,"max_ms":..,"total_s":..}, ...} */
	std::string toJson(int indent = 2) const;

   private:
	mutable std::mutex m_mutex;
	std::map<std::string, std::vector<double>> m_samples;  //!< guarded by m_mutex
};

}  // namespace keygrid::slam
