#pragma once
/** \file Interrupt.h
 * Cooperative interruption of long runs by Ctrl-C (SIGINT) or SIGTERM.
 *
 * The first signal only sets a flag: the frame loops poll interruptRequested(), stop reading
 * input, and the run still writes every output it has (report.json says "interrupted": true).
 * A second signal exits at once (status 128 + signal number), for when finishing takes too long.
 */

namespace keygrid::slam
{
/** Installs the SIGINT and SIGTERM handlers (idempotent). The handler is async-signal-safe:
 * it stores to a lock-free atomic, writes one fixed message with write(2) and, on a second
 * signal, calls _exit(2). */
void installInterruptHandlers();

/** True once SIGINT or SIGTERM arrived (or requestInterrupt() was called). */
bool interruptRequested();

/** The signal that requested the interruption (0 = none, or requestInterrupt()). */
int interruptSignal();

/** Sets the flag as a signal would (for tests and embedding applications). */
void requestInterrupt();

/** Clears the flag (a new run in the same process). */
void clearInterrupt();

}  // namespace keygrid::slam
