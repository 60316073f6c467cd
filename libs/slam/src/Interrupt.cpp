#include <keygrid/slam/Interrupt.h>

#include <atomic>
#include <csignal>
#include <cstring>
#include <unistd.h>

namespace keygrid::slam
{
namespace
{
// Only lock-free atomics may be touched from a signal handler.
std::atomic<int> g_signal{0};
std::atomic<bool> g_requested{false};
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free);

void writeStderr(const char* msg)
{
	// write(2) is async-signal-safe; its result cannot be acted upon here.
	const ssize_t n = ::write(STDERR_FILENO, msg, std::strlen(msg));
	(void)n;
}

extern "C" void onInterruptSignal(int sig)
{
	if (g_requested.exchange(true))
	{
		writeStderr("\nkeygrid: second interrupt, exiting immediately (outputs not written)\n");
		::_exit(128 + sig);
	}
	g_signal.store(sig);
	writeStderr(
		"\nkeygrid: interrupted, stopping after the current frame and writing the outputs "
		"(interrupt again to quit at once)\n");
}
}  // namespace

void installInterruptHandlers()
{
	struct sigaction sa;
	std::memset(&sa, 0, sizeof(sa));
	sa.sa_handler = &onInterruptSignal;
	sigemptyset(&sa.sa_mask);
	// SA_RESTART: blocking reads in worker threads resume instead of failing with EINTR.
	sa.sa_flags = SA_RESTART;
	sigaction(SIGINT, &sa, nullptr);
	sigaction(SIGTERM, &sa, nullptr);
}

bool interruptRequested() { return g_requested.load(); }

int interruptSignal() { return g_signal.load(); }

void requestInterrupt() { g_requested.store(true); }

void clearInterrupt()
{
	g_requested.store(false);
	g_signal.store(0);
}

}  // namespace keygrid::slam
