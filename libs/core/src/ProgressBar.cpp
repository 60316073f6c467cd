#include <keygrid/core/ProgressBar.h>
#include <unistd.h>

#include <cstdio>

namespace keygrid::core
{
ProgressBar::ProgressBar(std::string label, std::size_t total, bool enabled)
	: m_label(std::move(label)),
	  m_total(total),
	  m_enabled(enabled),
	  m_tty(isatty(fileno(stderr)) != 0),
	  m_start(std::chrono::steady_clock::now()),
	  m_lastDraw(m_start)
{
}

ProgressBar::~ProgressBar()
{
	if (!m_finished && m_enabled && m_tty && m_done > 0) std::fputc('\n', stderr);
}

double ProgressBar::elapsed() const
{
	return std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
}

void ProgressBar::update(std::size_t done, const std::string& extra)
{
	m_done = done;
	if (!m_enabled || m_finished) return;
	const auto now = std::chrono::steady_clock::now();
	const double sinceDraw = std::chrono::duration<double>(now - m_lastDraw).count();
	if (m_tty)
	{
		if (sinceDraw < 0.2) return;
	}
	else if (m_total > 0)
	{
		const int decile = static_cast<int>(10 * done / m_total);
		if (decile == m_lastDecile) return;
		m_lastDecile = decile;
	}
	else if (sinceDraw < 5.0)
		return;
	m_lastDraw = now;
	draw(done, extra, false);
}

void ProgressBar::finish(const std::string& extra)
{
	if (!m_enabled || m_finished) return;
	m_finished = true;
	// A log (non-terminal) already has the 100 % line unless there is something new to say.
	if (!m_tty && m_total > 0 && m_lastDecile == 10 && extra.empty()) return;
	draw(m_done, extra, true);
}

void ProgressBar::draw(std::size_t done, const std::string& extra, bool final)
{
	const double t = elapsed();
	char line[512];
	if (m_total > 0)
	{
		const double frac = done > m_total ? 1.0 : static_cast<double>(done) / m_total;
		const int width = 30, filled = static_cast<int>(frac * width);
		std::string bar(static_cast<std::size_t>(filled), '#');
		bar.resize(width, '.');
		std::snprintf(
			line, sizeof(line), "%s [%s] %zu/%zu %3.0f%% %.1fs %s", m_label.c_str(), bar.c_str(), done,
			m_total, 100.0 * frac, t, extra.c_str());
	}
	else
		std::snprintf(line, sizeof(line), "%s %zu done %.1fs %s", m_label.c_str(), done, t, extra.c_str());
	if (m_tty)
		std::fprintf(stderr, "\r%s\033[K%s", line, final ? "\n" : "");
	else
		std::fprintf(stderr, "%s\n", line);
	std::fflush(stderr);
}

}  // namespace keygrid::core
