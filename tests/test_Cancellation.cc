// SPDX-License-Identifier: Apache-2.0
/// @file test_Cancellation.cc
/// @brief A stop requested in any stage makes buildSurface(), SurfaceReconstructor and the
///        stage functions throw CancelledError("interrupted during <stage>"), and a
///        reconstructor stays usable afterwards. How fast a stop takes effect is measured
///        by tests/bench/CancelLatency.cc, not here.

#include "TestUtil.h"

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/ComputeNormals.h>
#include <nonbloppy/CorrectSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/EstimateParameters.h>
#include <nonbloppy/ParticleIndex.h>
#include <nonbloppy/Particles.h>
#include <nonbloppy/SurfaceReconstructor.h>

#include "../src/Cancellation.h"

#include <gtest/gtest.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>  // is_current_task_group_canceling

#include <atomic>
#include <chrono>
#include <new>
#include <string>
#include <thread>
#include <vector>

using namespace nonbloppy;
using nonbloppy_test::latticeParticles;

namespace {

/// The stages in the order buildSurface() runs them, as announced through start().
const char* const kStages[] = {"estimate parameters", "index particles", "rasterize density",
                               "extract surface",     "relax vertices",  "correct surface",
                               "compute normals",     "smooth surface"};

/// Runs only when the spacing is given (with the volume correction).
bool needsSpacing(const std::string& stage) { return stage == "smooth surface"; }

/// Says stop from the moment stage @a target is announced, ever after.
struct StopInStage : openvdb::util::NullInterrupter
{
    explicit StopInStage(std::string stage) : target(std::move(stage)) {}
    void start(const char* name) override
    {
        if (name && target == name) fired = true;
    }
    bool wasInterrupted(int = -1) override { return fired.load(); }
    std::string target;
    std::atomic<bool> fired{false};
};

/// Says stop from its n-th wasInterrupted() call on (n = 0: never); counts the calls.
struct StopAfterPolls : openvdb::util::NullInterrupter
{
    explicit StopAfterPolls(long n) : limit(n) {}
    bool wasInterrupted(int = -1) override { return ++polls >= limit && limit > 0; }
    long limit;
    std::atomic<long> polls{0};
};

std::vector<openvdb::Vec3f> ballFrame(double radius)
{
    return latticeParticles(0.1, radius + 0.1,
        [radius](const openvdb::Vec3d& x) { return x.length() < radius; }, 0.1, 5);
}

/// The spacing given, so that the volume correction runs too (a second "correct surface").
SurfaceParameters withSpacing()
{
    SurfaceParameters params;
    params.spacing = 0.1;
    return params;
}

template<typename FunctionT>
std::string cancelMessage(FunctionT&& function)
{
    try {
        function();
    } catch (const CancelledError& e) {
        return e.what();
    }
    return "(not cancelled)";
}

void expectSameBytes(const SurfaceMesh& a, const SurfaceMesh& b)
{
    EXPECT_EQ(a.points, b.points);
    EXPECT_EQ(a.normals, b.normals);
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(a.quads, b.quads);
}

} // namespace

TEST(Cancellation, EveryStageOfBuildSurfaceThrowsItsOwnMessage)
{
    const auto frame = ballFrame(0.5);
    for (const SurfaceParameters& params : {SurfaceParameters(), withSpacing()}) {
        for (const char* stage : kStages) {
            if (!params.spacing && needsSpacing(stage)) continue;
            SCOPED_TRACE(stage);
            StopInStage stop(stage);
            EXPECT_EQ(cancelMessage([&] { buildSurface(frame, params, &stop); }),
                      std::string("interrupted during ") + stage);
            EXPECT_TRUE(stop.fired) << "stage never announced";
        }
    }
}

TEST(Cancellation, ReconstructorStaysUsableAfterAStopInEveryStage)
{
    const auto frame = ballFrame(0.6);
    const SurfaceResult expected = buildSurface(frame, withSpacing());
    SurfaceReconstructor reconstructor(withSpacing());
    for (const char* stage : kStages) {
        SCOPED_TRACE(stage);
        StopInStage stop(stage);
        EXPECT_EQ(cancelMessage([&] { reconstructor.reconstruct(ParticleSet{frame, {}, {}}, &stop); }),
                  std::string("interrupted during ") + stage);
        const SurfaceResult& got = reconstructor.reconstruct(ParticleSet{frame, {}, {}});
        expectSameBytes(got.mesh, expected.mesh);
    }
    EXPECT_EQ(reconstructor.frameCount(), std::size(kStages));
}

TEST(Cancellation, StopAfterAnyNumberOfPollsNamesAStage)
{
    const auto frame = ballFrame(0.5);
    StopAfterPolls counter(0);
    const SurfaceResult expected = buildSurface(frame, withSpacing(), &counter);
    const long total = counter.polls;
    ASSERT_GT(total, 20);
    SurfaceReconstructor reconstructor(withSpacing());
    for (long n = 1; n < total; n += std::max(1L, total / 23)) {
        SCOPED_TRACE(n);
        StopAfterPolls stop(n);
        const std::string message =
            cancelMessage([&] { reconstructor.reconstruct(ParticleSet{frame, {}, {}}, &stop); });
        if (message == "(not cancelled)") {
            // The number of polls varies a little with the threads' split of the work.
            EXPECT_GT(n, total / 2);
            continue;
        }
        bool known = false;
        for (const char* stage : kStages) known |= message == std::string("interrupted during ") + stage;
        EXPECT_TRUE(known) << message;
        expectSameBytes(reconstructor.reconstruct(ParticleSet{frame, {}, {}}).mesh, expected.mesh);
    }
}

TEST(Cancellation, StageFunctionsThrowTheirStagesMessage)
{
    const auto frame = ballFrame(0.5);
    const SurfaceResult result = buildSurface(frame, withSpacing());
    StopAfterPolls stop(1);
    EXPECT_EQ(cancelMessage([&] { estimateSpacing(frame, kSpacingSamples, &stop); }),
              "interrupted during estimate parameters");
    EXPECT_EQ(cancelMessage([&] { resolveParameters(SurfaceParameters(), frame, &stop); }),
              "interrupted during estimate parameters");
    EXPECT_EQ(cancelMessage([&] { ParticleIndex::build(frame, 0.1, &stop); }),
              "interrupted during index particles");
    SurfaceMesh mesh = result.mesh;
    EXPECT_EQ(cancelMessage([&] { computeNormals(mesh, &stop); }), "interrupted during compute normals");
    mesh = result.mesh;
    EXPECT_EQ(cancelMessage([&] { repairFolds(mesh, result.mesh.points, kDefaultRepairRounds, &stop); }),
              "interrupted during correct surface");
    mesh = result.mesh;
    EXPECT_EQ(cancelMessage([&] { preserveVolume(mesh, 1.0, 0.01, &stop); }),
              "interrupted during correct surface");
    mesh = result.mesh;
    VolumeSettings convex;
    convex.targetVolume = 1.0;
    EXPECT_EQ(cancelMessage([&] { preserveVolume(mesh, convex, &stop); }),
              "interrupted during correct surface");
}

TEST(Cancellation, ThresholdCalibrationStopsWithinALargeIterationCount)
{
    // Calibrating r_0 relaxes sample vertices t times each; with so small a blend they never
    // settle, so t = 2³⁰ would take years unless the calibration itself polls.
    // The stop comes after twice the polls of a whole calibration at t = 2: beyond any
    // poll outside the relaxation steps.
    const auto frame = ballFrame(0.5);
    SurfaceParameters params;
    params.spacing = 0.1;
    params.blend = 1e-6;
    params.iterations = 2;
    StopAfterPolls counter(0);
    resolveParameters(params, frame, &counter);
    const long limit = 2 * counter.polls + 10;
    params.iterations = 1 << 30;
    StopAfterPolls stop(limit);
    EXPECT_EQ(cancelMessage([&] { resolveParameters(params, frame, &stop); }),
              "interrupted during estimate parameters");
    EXPECT_GE(stop.polls, limit);
}

TEST(Cancellation, AnInterrupterThatNeverFiresChangesNoByte)
{
    const auto frame = ballFrame(0.6);
    StopAfterPolls never(0);
    const SurfaceResult with = buildSurface(frame, withSpacing(), &never);
    const SurfaceResult without = buildSurface(frame, withSpacing());
    EXPECT_GT(never.polls, 0);
    expectSameBytes(with.mesh, without.mesh);
}

// A TBB algorithm whose sibling task throws (std::bad_alloc, say) is cancelled, and so are
// the loops of an OpenVDB tool running inside it, whose serial code then read what they
// never wrote: createPointIndexGrid() crashed so under ulimit -v. The tool's call runs
// isolated from that cancellation and completes every task, while the exception still
// reaches the caller.
TEST(RunIsolatedFromCancellation, ASiblingsExceptionCancelsNoTaskOfTheIsolatedWork)
{
    constexpr size_t kTasks = 64;
    for (const bool isolated : {false, true}) {
        std::atomic<bool> started{false}, thrown{false};
        std::atomic<size_t> ran{0};
        bool concurrent = true;
        tbb::task_arena arena(2);
        const auto waitFor = [](const std::atomic<bool>& flag) {
            const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
            while (!flag && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
            return bool(flag);
        };
        const auto loop = [&] {
            tbb::parallel_for(tbb::blocked_range<size_t>(0, kTasks, 1), [&](const tbb::blocked_range<size_t>& range) {
                ran += range.size();
            });
        };
        EXPECT_THROW(arena.execute([&] {
            tbb::parallel_invoke(
                [&] {
                    started = true;
                    concurrent = waitFor(thrown);
                    // Until the exception has cancelled this context (a fixed 20 ms sleep
                    // could end first on a loaded machine).
                    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
                    while (!tbb::is_current_task_group_canceling() && std::chrono::steady_clock::now() < deadline) {
                        std::this_thread::yield();
                    }
                    if (isolated) cancellation_internal::runIsolatedFromCancellation(loop);
                    else loop();
                },
                [&] {
                    if (!waitFor(started)) return;
                    thrown = true;
                    throw std::bad_alloc();
                });
        }), std::bad_alloc);
        if (!concurrent) GTEST_SKIP() << "the two branches did not run at once (one worker thread)";
        if (isolated) EXPECT_EQ(ran, kTasks);
        else EXPECT_LT(ran, kTasks) << "the hazard this test guards against no longer shows";
    }
}
