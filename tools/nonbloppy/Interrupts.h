// SPDX-License-Identifier: Apache-2.0
/// @file Interrupts.h
/// @brief How the commands that write files stop on SIGINT, SIGTERM and SIGHUP: a flag the
///        signal handler sets and the work polls, so that a run stops cleanly (exit 130, no
///        partial files) instead of dying mid-write.
///
/// @code
/// SignalHandlerScope signals;       // for the command's duration
/// ParticleSet particles = readParticles(in);
/// throwIfInterrupted();             // CancelledError("interrupted"): main() exits 130
/// @endcode

#ifndef NONBLOPPY_TOOL_INTERRUPTS_H
#define NONBLOPPY_TOOL_INTERRUPTS_H

#include <array>
#include <csignal>

namespace nonbloppy_tool {

/// For its lifetime: SIGINT, SIGTERM and SIGHUP (a closed terminal or ssh session) set the
/// flag interruptRequested() reads, for the run to stop cleanly (exit 130, no partial files,
/// a sequence's log summary written); repeats within a second are absorbed (timeout(1)
/// signals its child and then its whole process group; a double key press sends two
/// SIGINTs), a later one ends the process at once (the signal's default action: the run did
/// not stop on its own, it may be blocked reading a FIFO nobody writes); a SIGHUP that was
/// ignored (nohup) stays ignored. SIGPIPE is ignored: a reader of stdout that went away
/// ('| head -1') used to end the run silently with exit 141. SIGXFSZ is ignored too: under a
/// file-size limit (ulimit -f) it ended the run with exit 153 and left the temporary output
/// behind; ignored, the write fails with EFBIG ("File too large"), reported and cleaned up
/// like a full disk. The previous handlers are
/// restored at the end. One at a time (the flag is the process's).
class SignalHandlerScope
{
public:
    SignalHandlerScope();
    ~SignalHandlerScope();
    SignalHandlerScope(const SignalHandlerScope&) = delete;
    SignalHandlerScope& operator=(const SignalHandlerScope&) = delete;

private:
    static constexpr std::array<int, 3> kStopSignals{SIGINT, SIGTERM, SIGHUP};
    std::array<void (*)(int), 3> mOld{SIG_DFL, SIG_DFL, SIG_DFL};
    void (*mOldPipe)(int) = SIG_DFL;
    void (*mOldFileSize)(int) = SIG_DFL;
    void (*mOldAlarm)(int) = SIG_DFL;
};

/// Seconds after the first stop signal at which a run still reading its input, with no
/// output of its own in progress, ends with the signal's default action (exit 143 for
/// SIGTERM, 130 for SIGINT): a read can block without polling (opening a FIFO that nobody
/// writes: `timeout 20 nonbloppy mesh in.vtk` never ended, as timeout's two signals arrive
/// together and count as one request), and there is nothing to clean up then.
constexpr unsigned kStuckReadSeconds = 2;

/// For its lifetime the run reads an input that may block (see kStuckReadSeconds). Any
/// thread; scopes nest and overlap (a sequence reads a frame while it writes the last).
class InputReadScope
{
public:
    InputReadScope();
    ~InputReadScope();
    InputReadScope(const InputReadScope&) = delete;
    InputReadScope& operator=(const InputReadScope&) = delete;
};

/// For its lifetime the run has outputs it must finish or put back when it stops: the stuck
/// read's default action waits for it to end (OutputCleanup holds one). Any thread; nests.
class OutputsPendingScope
{
public:
    OutputsPendingScope();
    ~OutputsPendingScope();
    OutputsPendingScope(const OutputsPendingScope&) = delete;
    OutputsPendingScope& operator=(const OutputsPendingScope&) = delete;
};

/// True once a stop signal arrived within the current SignalHandlerScope. Lock-free; any thread.
bool interruptRequested();

/// @throw nonbloppy::CancelledError("interrupted") if interruptRequested().
void throwIfInterrupted();

} // namespace nonbloppy_tool

#endif // NONBLOPPY_TOOL_INTERRUPTS_H
