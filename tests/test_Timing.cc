// SPDX-License-Identifier: Apache-2.0
// StageTimings and ScopedStageTimer: wall-clock and process CPU time per stage.
#include <nonbloppy/Timing.h>

#include <gtest/gtest.h>

#include <chrono>
#include <ctime>
#include <thread>

using nonbloppy::ScopedStageTimer;
using nonbloppy::StageTimings;

namespace {

/// Keep this thread busy until the process has used @a seconds more CPU time.
void burnCpu(double seconds)
{
    const std::clock_t start = std::clock();
    volatile double sink = 0.0;
    while (double(std::clock() - start) / CLOCKS_PER_SEC < seconds) {
        for (int i = 0; i < 1000; ++i) sink = sink + 1.0;
    }
}

} // namespace

TEST(Timing, AStageCountsTheCpuTimeSpentInIt)
{
    StageTimings timings;
    {
        ScopedStageTimer timer(timings, "busy");
        // A little over 0.03 s: the stage's two clock readings, each divided before they
        // are subtracted, may put exactly 30,000 us just below 0.03.
        burnCpu(0.031);
    }
    {
        // Sleeping takes wall-clock time but next to no CPU time.
        ScopedStageTimer timer(timings, "idle");
        std::this_thread::sleep_for(std::chrono::milliseconds(30));
    }
    ASSERT_EQ(timings.entries.size(), 2u);
    const StageTimings::Entry& busy = timings.entries[0];
    const StageTimings::Entry& idle = timings.entries[1];
    EXPECT_EQ(busy.stage, "busy");
    EXPECT_GE(busy.cpuSeconds, 0.03);
    EXPECT_GE(idle.seconds, 0.03);
    EXPECT_LT(idle.cpuSeconds, 0.5 * idle.seconds);
    EXPECT_DOUBLE_EQ(timings.cpuTotal(), busy.cpuSeconds + idle.cpuSeconds);
    EXPECT_DOUBLE_EQ(timings.total(), busy.seconds + idle.seconds);
}

TEST(Timing, AddingTimingsSumsBothClocksPerStageInFirstSeenOrder)
{
    StageTimings a, b;
    a.add("read particles", 1.0, 0.5);
    a.add("extract surface", 2.0, 3.5);
    b.add("extract surface", 0.25, 0.5);
    b.add("write mesh", 0.125);
    a.add(b);
    ASSERT_EQ(a.entries.size(), 3u);
    EXPECT_EQ(a.entries[0].stage, "read particles");
    EXPECT_EQ(a.entries[1].stage, "extract surface");
    EXPECT_EQ(a.entries[1].seconds, 2.25);
    EXPECT_EQ(a.entries[1].cpuSeconds, 4.0);
    EXPECT_EQ(a.entries[2].stage, "write mesh");
    EXPECT_EQ(a.entries[2].cpuSeconds, 0.0);
    EXPECT_EQ(a.total(), 3.375);
    EXPECT_EQ(a.cpuTotal(), 4.5);
}
