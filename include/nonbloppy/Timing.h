// SPDX-License-Identifier: Apache-2.0
/// @file Timing.h
/// @brief Wall-clock and CPU time per pipeline stage, named as the stages are everywhere else
///        ("read particles", "rasterize density", "extract surface", ...).

#ifndef NONBLOPPY_TIMING_H
#define NONBLOPPY_TIMING_H

#include <chrono>
#include <ctime>
#include <string>
#include <vector>

namespace nonbloppy {

/// The process's CPU time so far, in seconds: every thread, user and system (std::clock());
/// 0 where the implementation cannot tell. Cost: one clock read.
inline double processCpuSeconds()
{
    const std::clock_t now = std::clock();
    return now == std::clock_t(-1) ? 0.0 : double(now) / CLOCKS_PER_SEC;
}

/// Seconds spent in each stage, in the order the stages ran.
///
/// CPU time is that of the whole process (processCpuSeconds()) while the stage ran, so
/// cpuSeconds / seconds is the number of cores the stage kept busy. It also counts whatever
/// else the process did meanwhile, such as another frame meshed on other threads: compare it
/// only for a process that runs one pipeline at a time.
struct StageTimings
{
    /// One stage's accumulated time.
    struct Entry
    {
        std::string stage;        ///< stage name, e.g. "rasterize density"
        double seconds = 0.0;     ///< wall-clock seconds
        double cpuSeconds = 0.0;  ///< CPU seconds of the whole process (see above)
    };
    std::vector<Entry> entries;  ///< in the order the stages first ran

    /// Add @a seconds of wall-clock time and @a cpuSeconds of CPU time to @a stage (appended
    /// the first time it is seen).
    void add(const std::string& stage, double seconds, double cpuSeconds = 0.0)
    {
        for (Entry& e : entries) {
            if (e.stage == stage) {
                e.seconds += seconds;
                e.cpuSeconds += cpuSeconds;
                return;
            }
        }
        entries.push_back({stage, seconds, cpuSeconds});
    }

    /// Add every entry of @a other (wall-clock and CPU time) to this one's.
    void add(const StageTimings& other)
    {
        for (const Entry& e : other.entries) add(e.stage, e.seconds, e.cpuSeconds);
    }

    /// Sum of all entries, wall-clock seconds.
    double total() const
    {
        double sum = 0.0;
        for (const Entry& e : entries) sum += e.seconds;
        return sum;
    }

    /// Sum of all entries, CPU seconds.
    double cpuTotal() const
    {
        double sum = 0.0;
        for (const Entry& e : entries) sum += e.cpuSeconds;
        return sum;
    }
};

/// Adds the wall-clock and process CPU time between its construction and destruction to one
/// stage of a StageTimings. Reads two clocks at each end (about a microsecond in all).
class ScopedStageTimer
{
public:
    /// Start timing @a stage; the time is added to @a timings on destruction.
    ScopedStageTimer(StageTimings& timings, std::string stage)
        : mTimings(timings), mStage(std::move(stage)), mStart(std::chrono::steady_clock::now()),
          mCpuStart(processCpuSeconds()) {}
    ~ScopedStageTimer()
    {
        const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - mStart;
        mTimings.add(mStage, elapsed.count(), processCpuSeconds() - mCpuStart);
    }
    ScopedStageTimer(const ScopedStageTimer&) = delete;
    ScopedStageTimer& operator=(const ScopedStageTimer&) = delete;

private:
    StageTimings& mTimings;
    std::string mStage;
    std::chrono::steady_clock::time_point mStart;
    double mCpuStart;  ///< processCpuSeconds() at construction
};

} // namespace nonbloppy

#endif // NONBLOPPY_TIMING_H
