/** \file BatchProcess.cpp
 * posix_spawn + a polling waitpid loop (polling keeps time limits simple and leaves other
 * children of the calling process alone).
 */
#include <keygrid/slam/apps/BatchProcess.h>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <thread>

extern char** environ;

namespace keygrid::slam
{
namespace
{
using Clock = std::chrono::steady_clock;

struct Running
{
	std::size_t index{0};
	pid_t pid{-1};
	Clock::time_point start;
	bool termSent{false};
	Clock::time_point termTime;
};

/** Starts one job; returns -1 and sets *error when it cannot be started. */
pid_t spawn(const ProcessJob& job, std::string* error)
{
	posix_spawn_file_actions_t fa;
	posix_spawn_file_actions_init(&fa);
	posix_spawn_file_actions_addopen(&fa, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
	posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, job.logPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
	posix_spawn_file_actions_adddup2(&fa, STDOUT_FILENO, STDERR_FILENO);
	std::vector<char*> argv;
	for (const auto& a : job.argv) argv.push_back(const_cast<char*>(a.c_str()));
	argv.push_back(nullptr);
	pid_t pid = -1;
	const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
	posix_spawn_file_actions_destroy(&fa);
	if (rc != 0)
	{
		*error = "cannot start " + job.argv[0] + ": " + std::strerror(rc);
		return -1;
	}
	return pid;
}
}  // namespace

std::string ProcessOutcome::describe() const
{
	if (!launchError.empty()) return launchError;
	if (timedOut) return "timed out after " + std::to_string(static_cast<long>(seconds)) + " s";
	if (signal != 0) return "killed by signal " + std::to_string(signal) + " (" + strsignal(signal) + ")";
	return "exit code " + std::to_string(exitCode);
}

std::vector<ProcessOutcome> runProcesses(
	const std::vector<ProcessJob>& jobs, int parallel, double timeoutSeconds,
	const std::function<void(std::size_t, const ProcessOutcome&)>& onDone)
{
	std::vector<ProcessOutcome> out(jobs.size());
	std::vector<Running> running;
	std::size_t next = 0;
	const auto finish = [&](std::size_t i) {
		if (onDone) onDone(i, out[i]);
	};
	while (next < jobs.size() || !running.empty())
	{
		while (next < jobs.size() && static_cast<int>(running.size()) < std::max(1, parallel))
		{
			const std::size_t i = next++;
			const pid_t pid = jobs[i].argv.empty() ? -1 : spawn(jobs[i], &out[i].launchError);
			if (jobs[i].argv.empty()) out[i].launchError = "empty command";
			if (pid < 0)
			{
				finish(i);
				continue;
			}
			running.push_back({i, pid, Clock::now(), false, {}});
		}
		bool reaped = false;
		for (auto it = running.begin(); it != running.end();)
		{
			ProcessOutcome& o = out[it->index];
			const auto now = Clock::now();
			o.seconds = std::chrono::duration<double>(now - it->start).count();
			int status = 0;
			const pid_t r = waitpid(it->pid, &status, WNOHANG);
			if (r == it->pid || (r < 0 && errno != EINTR))
			{
				if (r == it->pid && WIFEXITED(status)) o.exitCode = WEXITSTATUS(status);
				if (r == it->pid && WIFSIGNALED(status)) o.signal = WTERMSIG(status);
				if (r < 0) o.launchError = std::string("waitpid: ") + std::strerror(errno);
				const std::size_t index = it->index;
				it = running.erase(it);
				finish(index);
				reaped = true;
				continue;
			}
			if (timeoutSeconds > 0 && o.seconds > timeoutSeconds && !it->termSent)
			{
				o.timedOut = true;
				kill(it->pid, SIGTERM);
				it->termSent = true;
				it->termTime = now;
			}
			else if (it->termSent && std::chrono::duration<double>(now - it->termTime).count() > 5.0)
				kill(it->pid, SIGKILL);
			++it;
		}
		if (!reaped) std::this_thread::sleep_for(std::chrono::milliseconds(20));
	}
	return out;
}

std::string commandText(const std::vector<std::string>& argv)
{
	std::string s;
	for (const auto& a : argv)
	{
		if (!s.empty()) s += ' ';
		if (a.empty() || a.find_first_of(" \t\"'$\\;&|<>()*?") != std::string::npos)
		{
			s += '\'';
			for (char c : a) s += c == '\'' ? std::string("'\\''") : std::string(1, c);
			s += '\'';
		}
		else
			s += a;
	}
	return s;
}

}  // namespace keygrid::slam
