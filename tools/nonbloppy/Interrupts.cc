// SPDX-License-Identifier: Apache-2.0
/// @file Interrupts.cc
/// @brief The stop-signal handler and its flag (see Interrupts.h).

#include "Interrupts.h"

#include <nonbloppy/Error.h>

#include <algorithm>
#include <atomic>
#include <cstdint>

#include <time.h>
#include <unistd.h>

namespace nonbloppy_tool {

namespace {

/// Set by SIGINT, SIGTERM or SIGHUP; the mesh command's interrupter reports it to the
/// library, which then throws CancelledError at its next check.
std::atomic<bool> gInterruptRequested{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

/// When the first stop signal of the run arrived (CLOCK_MONOTONIC nanoseconds, never 0), or 0.
std::atomic<int64_t> gFirstStopSignalAt{0};
static_assert(std::atomic<int64_t>::is_always_lock_free, "the signal handler needs a lock-free clock");

/// Repeats of a stop signal within this time of the first are the same request. Ending the
/// run at once on the second of timeout(1)'s two signals cut short the clean-up and left this
/// run's mesh beside the previous run's .vdb (and a stray backup of the old mesh).
constexpr int64_t kRepeatedSignalNanoseconds = 1'000'000'000;

/// The first stop signal's number, for its default action once a read is stuck; 0 before.
std::atomic<int> gFirstStopSignal{0};
/// Live InputReadScope and OutputsPendingScope objects.
std::atomic<int> gInputReads{0};
std::atomic<int> gOutputsPending{0};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handlers need lock-free counters");

/// SIGALRM, kStuckReadSeconds after the first stop signal: the run has not stopped. If it is
/// reading its input with no output pending, it is blocked there (or reading for long without
/// a poll, which loses nothing): the first signal's default action. Otherwise it will stop at
/// its next poll or once its outputs are settled: asked again in a second.
extern "C" void onStopGraceOver(int)
{
    const int signalNumber = gFirstStopSignal.load();
    if (signalNumber != 0 && gInputReads.load() > 0 && gOutputsPending.load() == 0) {
        std::signal(signalNumber, SIG_DFL);
        std::raise(signalNumber);
        return;
    }
    ::alarm(1);
}

extern "C" void onInterruptSignal(int signalNumber)
{
    timespec now{};
    ::clock_gettime(CLOCK_MONOTONIC, &now);  // async-signal-safe
    const int64_t at = std::max<int64_t>(1, int64_t(now.tv_sec) * 1'000'000'000 + now.tv_nsec);
    int64_t first = 0;
    if (gFirstStopSignalAt.compare_exchange_strong(first, at)) {
        gFirstStopSignal = signalNumber;
        gInterruptRequested = true;
        ::alarm(kStuckReadSeconds);  // async-signal-safe, as are the counters onStopGraceOver() reads
        return;
    }
    // A signal a second or more after the first means "stop now": the run has not stopped on
    // its own (it may be blocked, say reading a FIFO that nobody writes). Default action.
    if (at - first >= kRepeatedSignalNanoseconds) {
        std::signal(signalNumber, SIG_DFL);
        std::raise(signalNumber);
    }
}

} // namespace

SignalHandlerScope::SignalHandlerScope()
{
    gInterruptRequested = false;
    gFirstStopSignalAt = 0;
    gFirstStopSignal = 0;
    mOldAlarm = std::signal(SIGALRM, onStopGraceOver);
    for (size_t n = 0; n < kStopSignals.size(); ++n) {
        mOld[n] = std::signal(kStopSignals[n], onInterruptSignal);
        if (kStopSignals[n] == SIGHUP && mOld[n] == SIG_IGN) std::signal(SIGHUP, SIG_IGN);
    }
    mOldPipe = std::signal(SIGPIPE, SIG_IGN);
    mOldFileSize = std::signal(SIGXFSZ, SIG_IGN);
}

SignalHandlerScope::~SignalHandlerScope()
{
    for (size_t n = 0; n < kStopSignals.size(); ++n) {
        std::signal(kStopSignals[n], mOld[n] == SIG_ERR ? SIG_DFL : mOld[n]);
    }
    std::signal(SIGPIPE, mOldPipe == SIG_ERR ? SIG_DFL : mOldPipe);
    std::signal(SIGXFSZ, mOldFileSize == SIG_ERR ? SIG_DFL : mOldFileSize);
    ::alarm(0);
    std::signal(SIGALRM, mOldAlarm == SIG_ERR ? SIG_DFL : mOldAlarm);
}

InputReadScope::InputReadScope() { ++gInputReads; }
InputReadScope::~InputReadScope() { --gInputReads; }
OutputsPendingScope::OutputsPendingScope() { ++gOutputsPending; }
OutputsPendingScope::~OutputsPendingScope() { --gOutputsPending; }

bool interruptRequested()
{
    return gInterruptRequested.load(std::memory_order_relaxed);
}

void throwIfInterrupted()
{
    if (interruptRequested()) throw nonbloppy::CancelledError("interrupted");
}

} // namespace nonbloppy_tool
