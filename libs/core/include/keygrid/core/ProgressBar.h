#pragma once
/** \file ProgressBar.h
 * Progress on long work, on stderr. On a terminal: one line redrawn at most 5 times a second.
 * Otherwise (logs, CI): a plain line at every 10 % (or every 5 s when the total is unknown).
 */
#include <chrono>
#include <cstddef>
#include <iosfwd>
#include <string>

namespace keygrid::core
{
class ProgressBar
{
   public:
	/** total == 0 means unknown. `enabled=false` prints nothing (e.g. --quiet). */
	ProgressBar(std::string label, std::size_t total, bool enabled = true);
	~ProgressBar();

	/** Reports `done` units finished, with optional extra text (e.g. "31.2 fps"). */
	void update(std::size_t done, const std::string& extra = "");
	/** Prints the final line once. */
	void finish(const std::string& extra = "");

	/** Seconds since construction. */
	double elapsed() const;

   private:
	void draw(std::size_t done, const std::string& extra, bool final);

	std::string m_label;
	std::size_t m_total;
	bool m_enabled, m_tty, m_finished{false};
	std::chrono::steady_clock::time_point m_start, m_lastDraw;
	int m_lastDecile{-1};
	std::size_t m_done{0};
};

}  // namespace keygrid::core
