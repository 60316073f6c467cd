#include <keygrid/slam/ProcessMemory.h>

#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace keygrid::slam
{
double residentMegabytes()
{
	// statm: size resident shared text lib data dt, in pages.
	std::FILE* f = std::fopen("/proc/self/statm", "r");
	if (!f) return 0;
	unsigned long size = 0, resident = 0;
	const int n = std::fscanf(f, "%lu %lu", &size, &resident);
	std::fclose(f);
	if (n != 2) return 0;
	return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

double peakResidentMegabytes()
{
	rusage u{};
	if (getrusage(RUSAGE_SELF, &u) != 0) return 0;
	return static_cast<double>(u.ru_maxrss) / 1024.0;  // Linux: kilobytes
}

MemorySampler::MemorySampler(std::size_t every) : m_every(every), m_next(every)
{
	if (every == 0) throw std::invalid_argument("MemorySampler: every must be >= 1 keyframe");
}

void MemorySampler::onFrame(std::size_t keyframes, std::size_t frames)
{
	if (keyframes >= m_next) onFrame(keyframes, frames, residentMegabytes());
}

void MemorySampler::onFrame(std::size_t keyframes, std::size_t frames, double rssMb)
{
	if (keyframes < m_next) return;
	m_samples.push_back({keyframes, frames, rssMb});
	m_next = (keyframes / m_every + 1) * m_every;
}

std::string MemorySampler::toJson() const
{
	std::ostringstream o;
	o << "[";
	for (std::size_t i = 0; i < m_samples.size(); i++)
	{
		char b[96];
		std::snprintf(b, sizeof(b), "%s[%zu, %zu, %.1f]", i ? ", " : "", m_samples[i].keyframes, m_samples[i].frames, m_samples[i].rssMb);
		o << b;
	}
	o << "]";
	return o.str();
}

}  // namespace keygrid::slam
