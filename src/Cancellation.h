// SPDX-License-Identifier: Apache-2.0
/// @file Cancellation.h
/// @brief Private: how the stages poll the caller's interrupter. Only src/ includes it.
///
/// Issue #7 asks that a cancel take effect within 100 ms on the 1.5M-particle benchmark
/// input, so every loop of nonbloppy's own that can run that long polls: parallel loops once
/// per task and every kItemsPerPoll items inside it, serial loops every kItemsPerPoll items
/// (about 0.1 ms of work at ~10 ns per item). OpenVDB's volumeToMesh and
/// createPointIndexGrid take no interrupter and cannot be stopped safely from outside
/// (cancelling their TBB context leaves uninitialised counts that they then allocate
/// from), so they are only checked before and after; the extraction stage therefore calls
/// volumeToMesh on slabs of the grid (extractByRegion() in SurfaceStages.h).

#ifndef NONBLOPPY_CANCELLATION_H
#define NONBLOPPY_CANCELLATION_H

#include <nonbloppy/Error.h>
#include <nonbloppy/Mesh.h>

#include <openvdb/util/NullInterrupter.h>

#include <tbb/task_group.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <string>
#include <thread>

namespace nonbloppy {
namespace cancellation_internal {

/// Items of a cheap inner loop (a particle, a polygon, a voxel row) between two polls.
constexpr size_t kItemsPerPoll = 4096;

/// Polls an optional interrupter on behalf of one stage and remembers a "stop".
class CancelPoll
{
public:
    /// @param interrupter  may be null (then nothing ever stops)
    /// @param stage        the stage's name, as in the timings ("relax vertices")
    CancelPoll(openvdb::util::NullInterrupter* interrupter, const char* stage)
        : mInterrupter(interrupter), mStage(stage) {}
    CancelPoll(const CancelPoll&) = delete;
    CancelPoll& operator=(const CancelPoll&) = delete;

    /// True once the interrupter has said stop: asks it (one wasInterrupted() call, with
    /// @a percent when ≥ 0) until it does, then answers from memory.
    /// Cost: an atomic load plus, until stopped, one virtual call.
    /// Thread-safety: callable from many tasks at once (wasInterrupted() then is too).
    bool stopped(int percent = -1)
    {
        if (!mInterrupter) return false;
        if (mStopped.load(std::memory_order_relaxed)) return true;
        if (!mInterrupter->wasInterrupted(percent)) return false;
        mStopped.store(true, std::memory_order_relaxed);
        return true;
    }

    /// stopped() every kItemsPerPoll-th value of a loop counter @a n (n = 0 included), else
    /// only the remembered answer: for the inner loops of tasks and serial loops.
    bool stoppedAt(size_t n)
    {
        return n % kItemsPerPoll == 0 ? stopped() : mStopped.load(std::memory_order_relaxed);
    }

    /// @throw CancelledError("interrupted during <stage>") if stopped().
    void throwIfStopped()
    {
        if (stopped()) throw CancelledError(std::string("interrupted during ") + mStage);
    }

    /// The stage's name.
    const char* stage() const { return mStage; }
    /// Whether there is an interrupter to ask at all.
    bool active() const { return mInterrupter != nullptr; }

private:
    openvdb::util::NullInterrupter* mInterrupter;
    const char* mStage;
    std::atomic<bool> mStopped{false};
};

/// Announces one stage to an optional interrupter: start(stage) on construction, end() on
/// destruction, also when the stage throws (a start() without its end() leaves a caller's
/// progress display in the stage). Cost: two virtual calls.
class AnnouncedStage
{
public:
    /// @param interrupter  may be null (then nothing is announced)
    AnnouncedStage(openvdb::util::NullInterrupter* interrupter, const char* stage) : mInterrupter(interrupter)
    {
        if (mInterrupter) mInterrupter->start(stage);
    }
    ~AnnouncedStage()
    {
        if (mInterrupter) mInterrupter->end();
    }
    AnnouncedStage(const AnnouncedStage&) = delete;
    AnnouncedStage& operator=(const AnnouncedStage&) = delete;

private:
    openvdb::util::NullInterrupter* mInterrupter;
};

/// computeNormals() reporting a stop under @a poll's stage (preserveVolume() calls it inside
/// "correct surface"). Defined in ComputeNormals.cc.
/// @throw CancelledError("interrupted during <poll's stage>")
void computeNormals(SurfaceMesh& mesh, CancelPoll& poll);

/// calibrateThreshold() asking @a poll before each of its samples of the lattice cell
/// (resolveParameters() calls it inside "estimate parameters"). Defined in
/// EstimateParameters.cc.
/// @throw CancelledError("interrupted during <poll's stage>"), or ParameterError as the
///        public function
double calibrateThreshold(double effectiveRadiusOverSpacing, CancelPoll& poll);

/// @a threshold, a calibrated r_0, if it is > 0. Defined in EstimateParameters.cc.
/// @throw ParameterError("--radius is too small to calibrate --threshold: ...") otherwise.
double requireCalibratedThreshold(double threshold, double effectiveRadiusOverSpacing);

/// calibrateRelaxedThreshold() asking @a poll before every relaxation step of a sample
/// vertex: its cost grows with t, which the caller chooses. Defined in CorrectSurface.cc.
/// @throw CancelledError("interrupted during <poll's stage>"), or ParameterError as the
///        public function
double calibrateRelaxedThreshold(double effectiveRadiusOverSpacing, double blend, int iterations,
                                 bool* reachesSurface, double maxStepOverSpacing, CancelPoll& poll);

/// Run @a work, parallel TBB code that polls nothing itself (tbb::parallel_sort), under a
/// TBB context of its own while a helper thread asks @a poll every millisecond and cancels
/// that context when it says stop: the TBB algorithms inside then skip their remaining
/// tasks and return. Only for work of nonbloppy's own whose partial result is thrown away
/// (the caller must check poll.stopped() afterwards); never for OpenVDB's tools, whose
/// serial code between parallel loops would run on partial data.
/// Cost: one thread start and join (~0.1 ms); without an interrupter, @a work alone.
template<typename WorkT>
void runStoppable(CancelPoll& poll, WorkT&& work)
{
    if (!poll.active()) { work(); return; }
    tbb::task_group_context context;
    std::mutex mutex;
    std::condition_variable wake;
    bool finished = false;
    std::thread watcher([&] {
        std::unique_lock<std::mutex> lock(mutex);
        while (!finished) {
            if (poll.stopped()) { context.cancel_group_execution(); return; }
            wake.wait_for(lock, std::chrono::milliseconds(1));
        }
    });
    const auto stopWatcher = [&] {
        { std::lock_guard<std::mutex> lock(mutex); finished = true; }
        wake.notify_one();
        watcher.join();
    };
    try {
        tbb::task_group group(context);
        group.run_and_wait([&] { work(); });
    } catch (...) {
        stopWatcher();
        throw;
    }
    stopWatcher();
}

/// Run @a work, a call of OpenVDB's parallel tools made inside a TBB algorithm of nonbloppy's
/// own (a parallel_invoke, a pipeline), under a TBB context isolated from the caller's. When
/// a sibling task throws (std::bad_alloc under ulimit -v, say), TBB cancels the caller's
/// context and every context bound to it: the tool's parallel loops then skip their tasks and
/// its serial code reads what they never wrote. createPointIndexGrid() crashed that way
/// (segfault in PointPartitioner's binning, exit 139, a 4M-particle CSV at ulimit -v 340000).
/// Isolated, the tool runs to its end; exceptions of @a work itself still reach the caller.
/// Cost: one task spawn (microseconds).
template<typename WorkT>
void runIsolatedFromCancellation(WorkT&& work)
{
    tbb::task_group_context context(tbb::task_group_context::isolated);
    tbb::task_group group(context);
    group.run_and_wait([&] { work(); });
}

} // namespace cancellation_internal
} // namespace nonbloppy

#endif // NONBLOPPY_CANCELLATION_H
