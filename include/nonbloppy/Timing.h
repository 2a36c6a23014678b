// SPDX-License-Identifier: Apache-2.0
/// @file Timing.h
/// @brief Wall-clock time per pipeline stage, named as the stages are everywhere else
///        ("read particles", "rasterize density", "extract surface", ...).

#ifndef NONBLOPPY_TIMING_H
#define NONBLOPPY_TIMING_H

#include <chrono>
#include <string>
#include <vector>

namespace nonbloppy {

/// Seconds spent in each stage, in the order the stages ran.
struct StageTimings
{
    /// One stage's accumulated time.
    struct Entry
    {
        std::string stage;     ///< stage name, e.g. "rasterize density"
        double seconds = 0.0;  ///< wall-clock seconds
    };
    std::vector<Entry> entries;  ///< in the order the stages first ran

    /// Add @a seconds to @a stage (appended the first time it is seen).
    void add(const std::string& stage, double seconds)
    {
        for (Entry& e : entries) {
            if (e.stage == stage) { e.seconds += seconds; return; }
        }
        entries.push_back({stage, seconds});
    }
    /// Sum of all entries, seconds.
    double total() const
    {
        double sum = 0.0;
        for (const Entry& e : entries) sum += e.seconds;
        return sum;
    }
};

/// Adds the time between its construction and destruction to one stage of a StageTimings.
class ScopedStageTimer
{
public:
    /// Start timing @a stage; the time is added to @a timings on destruction.
    ScopedStageTimer(StageTimings& timings, std::string stage)
        : mTimings(timings), mStage(std::move(stage)), mStart(std::chrono::steady_clock::now()) {}
    ~ScopedStageTimer()
    {
        const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - mStart;
        mTimings.add(mStage, elapsed.count());
    }
    ScopedStageTimer(const ScopedStageTimer&) = delete;
    ScopedStageTimer& operator=(const ScopedStageTimer&) = delete;

private:
    StageTimings& mTimings;
    std::string mStage;
    std::chrono::steady_clock::time_point mStart;
};

} // namespace nonbloppy

#endif // NONBLOPPY_TIMING_H
