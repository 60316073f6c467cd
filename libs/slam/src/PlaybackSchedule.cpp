#include <keygrid/slam/PlaybackSchedule.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace keygrid::slam
{
PlaybackSchedule::PlaybackSchedule(double rate) : m_rate(rate)
{
	if (!(rate > 0) || !std::isfinite(rate))
		throw std::invalid_argument("PlaybackSchedule: rate " + std::to_string(rate) + " is not a positive finite factor");
}

double PlaybackSchedule::release(double timestamp)
{
	if (m_lastStamp && timestamp > *m_lastStamp) m_due += std::min((timestamp - *m_lastStamp) / m_rate, kMaxGap);
	if (!m_lastStamp || timestamp > *m_lastStamp) m_lastStamp = timestamp;
	return m_due;
}

}  // namespace keygrid::slam
