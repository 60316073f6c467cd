#include <keygrid/slam/StageTimings.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace keygrid::slam
{
StageTimings::Summary StageTimings::summary(const std::string& stage) const
{
	Summary s;
	std::vector<double> v;
	{
		std::lock_guard<std::mutex> lk(m_mutex);
		auto it = m_samples.find(stage);
		if (it == m_samples.end() || it->second.empty()) return s;
		v = it->second;
	}
	std::sort(v.begin(), v.end());
	s.count = v.size();
	for (double x : v) s.total += x;
	s.mean = s.total / v.size();
	s.median = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
	// Nearest-rank percentile.
	const std::size_t k = static_cast<std::size_t>(std::ceil(0.95 * v.size()));
	s.p95 = v[std::min(v.size() - 1, k == 0 ? 0 : k - 1)];
	s.max = v.back();
	return s;
}

std::vector<std::string> StageTimings::stages() const
{
	std::lock_guard<std::mutex> lk(m_mutex);
	std::vector<std::string> out;
	for (const auto& [k, v] : m_samples) out.push_back(k);
	return out;
}

std::vector<double> StageTimings::blockMeans(const std::string& stage, std::size_t block) const
{
	if (block == 0) throw std::invalid_argument("StageTimings::blockMeans: block must be >= 1");
	std::lock_guard<std::mutex> lk(m_mutex);
	std::vector<double> out;
	const auto it = m_samples.find(stage);
	if (it == m_samples.end()) return out;
	const auto& v = it->second;
	for (std::size_t b = 0; b < v.size(); b += block)
	{
		const std::size_t e = std::min(v.size(), b + block);
		double sum = 0;
		for (std::size_t i = b; i < e; i++) sum += v[i];
		out.push_back(sum / static_cast<double>(e - b));
	}
	return out;
}

std::string StageTimings::toJson(int indent) const
{
	std::ostringstream o;
	const std::string pad(static_cast<std::size_t>(indent), ' ');
	o << "{\n";
	bool first = true;
	for (const auto& name : stages())
	{
		const auto s = summary(name);
		char b[256];
		std::snprintf(
			b, sizeof(b),
			"%s  \"%s\": {\"count\": %zu, \"median_ms\": %.3f, \"p95_ms\": %.3f, \"mean_ms\": %.3f, \"max_ms\": %.3f, \"total_s\": %.3f}",
			pad.c_str(), name.c_str(), s.count, 1e3 * s.median, 1e3 * s.p95, 1e3 * s.mean, 1e3 * s.max, s.total);
		o << (first ? "" : ",\n") << b;
		first = false;
	}
	o << "\n" << pad << "}";
	return o.str();
}

}  // namespace keygrid::slam
