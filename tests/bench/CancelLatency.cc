// SPDX-License-Identifier: Apache-2.0
// Measures how long buildSurface() takes to throw CancelledError after an interrupter
// starts returning true, with the request placed inside each stage in turn.
//   usage: nonbloppy_cancel_latency <particles.vtk> [tiles per axis = 4]

#include "BenchUtil.h"

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/Error.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

using Clock = std::chrono::steady_clock;

// Returns true from the moment cancel() is called; remembers the stage last started.
struct FlagInterrupter : openvdb::util::NullInterrupter
{
    std::atomic<bool> flag{false};
    std::atomic<const char*> stage{"(before the first start())"};
    void start(const char* name) override { stage = name; }
    bool wasInterrupted(int = -1) override { return flag.load(std::memory_order_relaxed); }
};

int main(int argc, char** argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s particles.vtk [tiles]\n", argv[0]);
        return 2;
    }
    const int tiles = argc > 2 ? std::atoi(argv[2]) : 4;
    openvdb::initialize();
    const std::vector<openvdb::Vec3f> positions = nonbloppy_bench::tiledFrame(argv[1], tiles);
    std::printf("%zu particles, %u hardware threads\n", positions.size(), std::thread::hardware_concurrency());

    // One uncancelled run gives the stage boundaries.
    const nonbloppy::SurfaceResult full = nonbloppy::buildSurface(positions);
    std::vector<std::pair<std::string, double>> stageEnds;
    double t = 0.0;
    for (const auto& e : full.timings.entries) {
        std::printf("  %-20s %8.1f ms\n", e.stage.c_str(), 1e3 * e.seconds);
        stageEnds.emplace_back(e.stage, t + e.seconds);
        t += e.seconds;
    }

    // Cancel at 10%, 50% and 90% into each stage. Stages that announce themselves through
    // start() (rasterize density, extract surface, relax vertices) are timed from that call,
    // the others from the start of the run, using the stage times of the run above.
    double worst = 0.0;
    double stageStart = 0.0;
    for (const auto& [name, end] : stageEnds) {
        const double duration = end - stageStart;
        const bool announced = name == "rasterize density" || name == "extract surface" ||
                               name == "relax vertices";
        for (double fraction : {0.1, 0.5, 0.9}) {
            const double delay = announced ? fraction * duration : stageStart + fraction * duration;
            FlagInterrupter interrupter;
            std::atomic<bool> done{false};
            Clock::time_point requested;
            std::thread canceller([&] {
                if (announced) {
                    while (!done && name != interrupter.stage.load()) {
                        std::this_thread::sleep_for(std::chrono::microseconds(200));
                    }
                }
                const Clock::time_point from = Clock::now();
                while (!done && Clock::now() - from < std::chrono::duration<double>(delay)) {
                    std::this_thread::sleep_for(std::chrono::microseconds(200));
                }
                requested = Clock::now();
                interrupter.flag = true;
            });
            // buildSurface takes its vector by value: copy before starting the clock.
            std::vector<openvdb::Vec3f> copy = positions;
            std::string outcome = "finished";
            const Clock::time_point begin = Clock::now();
            try {
                nonbloppy::buildSurface(std::move(copy), nonbloppy::SurfaceParameters(), &interrupter);
            } catch (const nonbloppy::CancelledError& e) {
                outcome = e.what();
            }
            const Clock::time_point stop = Clock::now();
            done = true;
            canceller.join();
            const bool cancelled = outcome != "finished";
            const double latency = std::chrono::duration<double>(stop - requested).count();
            if (cancelled && latency > worst) worst = latency;
            std::printf("cancel %3.0f%% into %-18s: %s  [%s; run %.1f ms]\n", 100 * fraction,
                        name.c_str(),
                        cancelled ? ("latency " + std::to_string(int(1e3 * latency + 0.5)) + " ms").c_str()
                                  : "(finished before the request)",
                        outcome.c_str(), 1e3 * std::chrono::duration<double>(stop - begin).count());
            std::fflush(stdout);
        }
        stageStart = end;
    }
    std::printf("worst latency %.1f ms (target < 100 ms)\n", 1e3 * worst);
    return 0;
}
