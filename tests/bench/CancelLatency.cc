// SPDX-License-Identifier: Apache-2.0
// Measures how long buildSurface() takes to stop (return with CancelledError) after an
// interrupter starts returning true, with the request placed 10%, 50% and 90% into each
// stage, and prints the worst latency per stage, by the stage that was running when the
// request came (its last start()). A run that finishes although the request came before its
// end is listed apart: the request came after the last check, when only freeing was left.
//   usage: nonbloppy_cancel_latency <particles.vtk> [tiles per axis = 4] [--time-only N]
//                                   [--no-keep-density]
// --time-only N: only N uncancelled runs (with an interrupter that never fires, so its polls
// are paid), to compare the frame time before and after a change.
// --no-keep-density: SurfaceParameters::keepDensity = false, as `nonbloppy mesh` without
// --vdb (the deep interior is tiled, so volumeToMesh scans fewer voxels).

#include "BenchUtil.h"

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/Error.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>

using Clock = std::chrono::steady_clock;

// Returns true from the moment `flag` is set; remembers which stages announced themselves.
struct FlagInterrupter : openvdb::util::NullInterrupter
{
    std::atomic<bool> flag{false};
    std::atomic<const char*> stage{"(before the first start())"};
    std::mutex mutex;
    std::set<std::string> started;
    void start(const char* name) override
    {
        stage = name;
        std::lock_guard<std::mutex> lock(mutex);
        started.insert(name);
    }
    bool wasInterrupted(int = -1) override { return flag.load(std::memory_order_relaxed); }
};

int main(int argc, char** argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s particles.vtk [tiles] [--time-only N]\n", argv[0]);
        return 2;
    }
    const int tiles = argc > 2 ? std::atoi(argv[2]) : 4;
    int timeOnly = 0;
    nonbloppy::SurfaceParameters params;
    for (int a = 3; a < argc; ++a) {
        if (std::strcmp(argv[a], "--time-only") == 0 && a + 1 < argc) timeOnly = std::atoi(argv[++a]);
        else if (std::strcmp(argv[a], "--no-keep-density") == 0) params.keepDensity = false;
    }
    openvdb::initialize();
    const std::vector<openvdb::Vec3f> positions = nonbloppy_bench::tiledFrame(argv[1], tiles);
    std::printf("%zu particles, %u hardware threads, keepDensity %s\n", positions.size(),
                std::thread::hardware_concurrency(), params.keepDensity ? "true" : "false");

    // Uncancelled runs give the stage durations (and, with --time-only, the frame time).
    std::vector<std::pair<std::string, double>> stages;
    std::set<std::string> announced;
    std::vector<double> totals;
    for (int run = 0; run < std::max(1, timeOnly); ++run) {
        FlagInterrupter never;
        const Clock::time_point begin = Clock::now();
        auto full = std::make_unique<nonbloppy::SurfaceResult>(nonbloppy::buildSurface(positions, params, &never));
        totals.push_back(std::chrono::duration<double>(Clock::now() - begin).count());
        std::printf("uncancelled run %d: %.3f s (%zu vertices)\n", run + 1, totals.back(), full->mesh.points.size());
        stages.clear();
        for (const auto& e : full->timings.entries) {
            std::printf("  %-20s %8.1f ms\n", e.stage.c_str(), 1e3 * e.seconds);
            stages.emplace_back(e.stage, e.seconds);
        }
        announced = never.started;
        // A cancelled run frees what it built too: this is the floor of every latency.
        const Clock::time_point freeing = Clock::now();
        full.reset();
        std::printf("  (freeing the result: %.1f ms)\n",
                    1e3 * std::chrono::duration<double>(Clock::now() - freeing).count());
    }
    std::sort(totals.begin(), totals.end());
    std::printf("frame time: median %.3f s, min %.3f s over %zu runs\n", totals[totals.size() / 2],
                totals.front(), totals.size());
    if (timeOnly) return 0;

    // A stage the library announces through start() is timed from that call; otherwise from
    // the start of the run, using the stage times above (less exact under load).
    std::map<std::string, double> worstPerStage;
    double worst = 0.0;
    double stageStart = 0.0;
    for (const auto& [name, duration] : stages) {
        const bool isAnnounced = announced.count(name) > 0;
        for (double fraction : {0.1, 0.5, 0.9}) {
            const double delay = isAnnounced ? fraction * duration : stageStart + fraction * duration;
            FlagInterrupter interrupter;
            std::atomic<bool> done{false};
            std::atomic<bool> requestedFlag{false};
            Clock::time_point requested;
            std::string stageAtRequest;
            std::thread canceller([&] {
                if (isAnnounced) {
                    while (!done && name != interrupter.stage.load()) {
                        std::this_thread::sleep_for(std::chrono::microseconds(200));
                    }
                }
                const Clock::time_point from = Clock::now();
                while (!done && Clock::now() - from < std::chrono::duration<double>(delay)) {
                    std::this_thread::sleep_for(std::chrono::microseconds(200));
                }
                if (done) return;
                requested = Clock::now();
                stageAtRequest = interrupter.stage.load();
                requestedFlag = true;
                interrupter.flag = true;
            });
            // buildSurface takes its vector by value: copy before starting the clock.
            std::vector<openvdb::Vec3f> copy = positions;
            std::string outcome = "finished";
            const Clock::time_point begin = Clock::now();
            try {
                nonbloppy::buildSurface(std::move(copy), params, &interrupter);
            } catch (const nonbloppy::CancelledError& e) {
                outcome = e.what();
            }
            const Clock::time_point stop = Clock::now();
            done = true;
            canceller.join();
            const double run = std::chrono::duration<double>(stop - begin).count();
            if (!requestedFlag) {
                std::printf("cancel %3.0f%% into %-19s: (finished before the request)  [run %.1f ms]\n",
                            100 * fraction, name.c_str(), 1e3 * run);
                continue;
            }
            const double latency = std::chrono::duration<double>(stop - requested).count();
            const bool cancelled = outcome != "finished";
            if (cancelled) {
                worst = std::max(worst, latency);
                worstPerStage[stageAtRequest] = std::max(worstPerStage[stageAtRequest], latency);
            }
            std::printf("cancel %3.0f%% into %-19s: latency %5.0f ms  [request in %s; %s; run %.1f ms]\n",
                        100 * fraction, name.c_str(), 1e3 * latency, stageAtRequest.c_str(),
                        cancelled ? outcome.c_str() : "finished: request after the last check", 1e3 * run);
            std::fflush(stdout);
        }
        stageStart += duration;
    }
    std::printf("\nworst latency per stage the request came in (target < 100 ms):\n");
    for (const auto& [name, duration] : stages) {
        const auto it = worstPerStage.find(name);
        if (it == worstPerStage.end()) std::printf("  %-20s %8s\n", name.c_str(), "-");
        else std::printf("  %-20s %8.0f ms%s\n", name.c_str(), 1e3 * it->second, it->second < 0.1 ? "" : "  (over)");
    }
    std::printf("worst latency %.1f ms (target < 100 ms)\n", 1e3 * worst);
    return 0;
}
