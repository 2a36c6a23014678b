// SPDX-License-Identifier: Apache-2.0
// Meshes a sequence of frames twice, with buildSurface() per frame and with one
// SurfaceReconstructor, and reports per frame: time, operator-new calls and bytes, and
// minor page faults (fresh memory touched). Not a unit test: run it by hand.
//   usage: nonbloppy_reconstructor_bench <particles.vtk> [tiles per axis = 2] [frames = 6]

#include "BenchUtil.h"

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/SurfaceReconstructor.h>

#include <sys/resource.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <new>

namespace {
std::atomic<size_t> gNewCalls{0}, gNewBytes{0};
}

// GCC cannot see that the replaced operator new below pairs malloc with free.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

// Count every global operator new (std::vector, OpenVDB nodes, TBB tasks' own new).
void* operator new(size_t size)
{
    gNewCalls.fetch_add(1, std::memory_order_relaxed);
    gNewBytes.fetch_add(size, std::memory_order_relaxed);
    if (void* p = std::malloc(size ? size : 1)) return p;
    throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }

namespace {

long minorFaults()
{
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_minflt;
}

struct Sample { double seconds; size_t calls, bytes; long faults; size_t vertices; };

template<typename F>
Sample measure(F&& run)
{
    const size_t calls = gNewCalls, bytes = gNewBytes;
    const long faults = minorFaults();
    const auto start = std::chrono::steady_clock::now();
    const size_t vertices = run();
    return {nonbloppy_bench::secondsSince(start), gNewCalls - calls, gNewBytes - bytes,
            minorFaults() - faults, vertices};
}

void print(const char* label, int frame, const Sample& s)
{
    std::printf("%-14s frame %d: %7.1f ms  %8zu new calls  %8.1f MB new  %7ld page faults  %zu vertices\n",
                label, frame, 1e3 * s.seconds, s.calls, s.bytes / 1048576.0, s.faults, s.vertices);
}

} // namespace

int main(int argc, char** argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s particles.vtk [tiles] [frames]\n", argv[0]);
        return 2;
    }
    const int tiles = argc > 2 ? std::atoi(argv[2]) : 2;
    const int frames = argc > 3 ? std::atoi(argv[3]) : 6;
    openvdb::initialize();
    std::vector<std::vector<openvdb::Vec3f>> sequence;
    for (int f = 0; f < frames; ++f) sequence.push_back(nonbloppy_bench::tiledFrame(argv[1], tiles, 0.01 * f));
    std::printf("%d frames of %zu particles\n", frames, sequence[0].size());
    nonbloppy::SurfaceParameters params;
    params.spacing = nonbloppy::estimateSpacing(sequence[0]);  // same parameters for both

    Sample totalA{0, 0, 0, 0, 0}, totalB{0, 0, 0, 0, 0};
    nonbloppy::SurfaceReconstructor reconstructor(params);
    for (int round = 0; round < 2; ++round) {
        for (int f = 0; f < frames; ++f) {
            const nonbloppy::PositionArrayView<float> view(sequence[f].data()->asPointer(), sequence[f].size());
            // Interleaved, so both see the same machine load; frame 0 warms up and is skipped.
            const Sample a = measure([&] { return nonbloppy::buildSurface(view, params).mesh.points.size(); });
            const Sample b = measure([&] { return reconstructor.reconstruct(view).mesh.points.size(); });
            if (round == 1) {
                print("buildSurface", f, a);
                print("reconstructor", f, b);
                if (f > 0) {
                    totalA = {totalA.seconds + a.seconds, totalA.calls + a.calls, totalA.bytes + a.bytes,
                              totalA.faults + a.faults, 0};
                    totalB = {totalB.seconds + b.seconds, totalB.calls + b.calls, totalB.bytes + b.bytes,
                              totalB.faults + b.faults, 0};
                }
            }
        }
    }
    const double n = frames - 1;
    std::printf("mean over frames 1..%d:\n", frames - 1);
    std::printf("  buildSurface : %7.1f ms  %8.0f new calls  %7.1f MB  %8.0f page faults\n",
                1e3 * totalA.seconds / n, totalA.calls / n, totalA.bytes / n / 1048576.0, totalA.faults / n);
    std::printf("  reconstructor: %7.1f ms  %8.0f new calls  %7.1f MB  %8.0f page faults\n",
                1e3 * totalB.seconds / n, totalB.calls / n, totalB.bytes / n / 1048576.0, totalB.faults / n);
    return 0;
}
