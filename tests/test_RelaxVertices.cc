// SPDX-License-Identifier: Apache-2.0
#include "TestUtil.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/ExtractSurface.h>
#include <nonbloppy/Kernel.h>
#include <nonbloppy/ParticleIndex.h>
#include <nonbloppy/RasterizeDensity.h>
#include <nonbloppy/RelaxVertices.h>

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <string>

using namespace nonbloppy;

namespace {

const openvdb::Vec3f kCentre(12.31f, -4.17f, 0.05f);  // away from the origin on purpose

struct OneParticle
{
    ParticleIndex index = ParticleIndex::build({kCentre}, 0.5);
    SurfaceMesh mesh;
    OneParticle()
    {
        DensitySettings settings;
        settings.effectiveRadius = 1.0;
        settings.voxelSize = 0.05;
        mesh = extractSurface(*rasterizeDensity(index, settings), 1.0);
        // A sphere of radius r_e/(1+r_0) = 0.5 at h = 0.05 (about 4πr²/h² = 1257 quads): the
        // tests' per-vertex loops have vertices to check.
        EXPECT_GT(mesh.points.size(), 1000u);
    }
};

RelaxSettings relaxSettings(double blend, int iterations)
{
    RelaxSettings settings;
    settings.effectiveRadius = 1.0;
    settings.blend = blend;
    settings.iterations = iterations;
    return settings;
}

} // namespace

TEST(RelaxVertices, OneParticleShrinksEveryVertexByOneMinusCToTheT)
{
    for (const double blend : {0.3, 0.5, 1.0}) {
        for (const int iterations : {1, 2, 4}) {
            OneParticle one;
            const std::vector<openvdb::Vec3s> before = one.mesh.points;
            relaxVertices(one.mesh, one.index, relaxSettings(blend, iterations));
            const double factor = std::pow(1.0 - blend, iterations);
            for (size_t i = 0; i < before.size(); ++i) {
                const double d0 = (before[i] - kCentre).length();
                const double d = (one.mesh.points[i] - kCentre).length();
                ASSERT_NEAR(d, factor * d0, 1e-4 * d0 + (factor == 0.0 ? 1e-6 : 0.0))
                    << "c = " << blend << ", t = " << iterations << ", vertex " << i;
            }
        }
    }
}

TEST(RelaxVertices, ZeroBlendOrZeroIterationsLeaveVerticesUnchanged)
{
    OneParticle one;
    const std::vector<openvdb::Vec3s> before = one.mesh.points;
    relaxVertices(one.mesh, one.index, relaxSettings(0.0, 5));
    EXPECT_EQ(one.mesh.points, before);
    relaxVertices(one.mesh, one.index, relaxSettings(0.7, 0));
    EXPECT_EQ(one.mesh.points, before);
}

TEST(RelaxVertices, VertexWithNoParticleInReachStaysPut)
{
    OneParticle one;
    one.mesh.points.push_back(kCentre + openvdb::Vec3s(3.0f, 0.0f, 0.0f));
    relaxVertices(one.mesh, one.index, relaxSettings(0.5, 3));
    EXPECT_EQ(one.mesh.points.back(), kCentre + openvdb::Vec3s(3.0f, 0.0f, 0.0f));
}

TEST(RelaxVertices, AnEmptyIndexLeavesEveryVertexPut)
{
    // A default-constructed index (also SurfaceReconstructor::particleIndex() before its
    // first frame) segfaulted here and in rasterizeDensity(): it had no grid.
    OneParticle one;
    const std::vector<openvdb::Vec3s> before = one.mesh.points;
    for (const ParticleIndex& empty : {ParticleIndex(), ParticleIndex::build({}, 0.5)}) {
        EXPECT_EQ(empty.size(), 0u);
        relaxVertices(one.mesh, empty, relaxSettings(0.5, 2));
        EXPECT_EQ(one.mesh.points, before);
        DensitySettings settings;
        settings.effectiveRadius = 1.0;
        settings.voxelSize = 0.05;
        EXPECT_EQ(rasterizeDensity(empty, settings)->activeVoxelCount(), 0u);
    }
}

TEST(RelaxVertices, MovesTowardsTheWeightedMeanOfTwoParticles)
{
    // Vertex at the origin, particles at distances 0.25 (w = 3) and 0.5 (w = 1) on the x axis:
    // mean = (3·0.25 + 1·(−0.5)) / 4 = 0.0625; with c = 0.5 the vertex lands at 0.03125.
    const ParticleIndex index = ParticleIndex::build({openvdb::Vec3f(0.25f, 0, 0), openvdb::Vec3f(-0.5f, 0, 0)}, 0.5);
    SurfaceMesh mesh;
    mesh.points.push_back(openvdb::Vec3s(0.0f));
    relaxVertices(mesh, index, relaxSettings(0.5, 1));
    EXPECT_NEAR(mesh.points[0][0], 0.03125f, 1e-6f);
    EXPECT_EQ(mesh.points[0][1], 0.0f);
    EXPECT_EQ(mesh.points[0][2], 0.0f);
}

TEST(RelaxVertices, PiecesFarApartRelaxAsEachWouldAlone)
{
    // Two one-particle spheres far apart: 3000 on every axis puts 2000^3 = 8e9 groups of 3
    // index cells (1.5) in their box, more than the 2^32 the radix sort's keys can rank, so
    // the vertices are grouped by the comparison sort; 4e6 on x puts 2.7e6 groups between
    // them, more than the 2^21 per axis its keys once held (such a frame, a particle flung
    // far away, was refused after its density and surface were done). Each vertex sees only
    // its own particle either way: the joint result is each piece's own, bit for bit.
    for (const openvdb::Vec3f& offset : {openvdb::Vec3f(3000.0f), openvdb::Vec3f(4.0e6f, 0.0f, 0.0f)}) {
        SCOPED_TRACE(offset);
        const openvdb::Vec3f farCentre = kCentre + offset;
        DensitySettings density;
        density.effectiveRadius = 1.0;
        density.voxelSize = 0.05;
        const auto sphereAt = [&](const openvdb::Vec3f& centre) {
            return extractSurface(*rasterizeDensity(ParticleIndex::build({centre}, 0.5), density), 1.0);
        };
        SurfaceMesh near = sphereAt(kCentre), far = sphereAt(farCentre);
        SurfaceMesh both;
        both.points = near.points;
        both.points.insert(both.points.end(), far.points.begin(), far.points.end());
        ASSERT_GT(near.points.size(), 100u);
        ASSERT_GT(far.points.size(), 0u);

        const RelaxSettings settings = relaxSettings(0.3, 2);
        relaxVertices(both, ParticleIndex::build({kCentre, farCentre}, 0.5), settings);
        relaxVertices(near, ParticleIndex::build({kCentre}, 0.5), settings);
        relaxVertices(far, ParticleIndex::build({farCentre}, 0.5), settings);
        for (size_t i = 0; i < near.points.size(); ++i) ASSERT_EQ(both.points[i], near.points[i]) << i;
        for (size_t i = 0; i < far.points.size(); ++i) {
            ASSERT_EQ(both.points[near.points.size() + i], far.points[i]) << i;
        }
        // And they did move: by 1 − 0.7² of their distance to the particle.
        EXPECT_NEAR((near.points[0] - kCentre).length(), 0.49 * 0.5, 0.01);
    }
}

TEST(RelaxVertices, VerticesPastIntCellNumbersStayWhereTheyAre)
{
    // Vertices 2^31 to 3·2^31 index cells out got past the out-of-reach filter (which
    // counts grouping cells, 3 index cells wide), and the particle search from there walked
    // from cell INT_MIN for minutes (API review). They have no particle in reach and stay.
    const std::vector<openvdb::Vec3f> particles = {openvdb::Vec3f(0.0f), openvdb::Vec3f(0.3f, 0.0f, 0.0f)};
    const double cell = 0.5;
    const float far = float(1.2 * double(std::numeric_limits<int>::max()) * cell);
    SurfaceMesh mesh;
    mesh.points = {openvdb::Vec3s(0.0f, 0.5f, 0.0f), openvdb::Vec3s(far, 0.0f, 0.0f),
                   openvdb::Vec3s(0.0f, 0.0f, -far), openvdb::Vec3s(far, far, -far)};
    const std::vector<openvdb::Vec3s> start = mesh.points;
    relaxVertices(mesh, ParticleIndex::build(particles, cell), relaxSettings(0.5, 2));
    EXPECT_NE(mesh.points[0], start[0]);  // pulled towards the particles
    for (size_t i = 1; i < start.size(); ++i) EXPECT_EQ(mesh.points[i], start[i]) << "vertex " << i;
}

TEST(RelaxVertices, VerticesThatTravelFarMatchTheDirectSum)
{
    // Vertices are grouped by cell once, before the first iteration. With c = 1 each step
    // moves a vertex all the way to its weighted mean: vertices starting up to 0.95 r_e from a
    // block of particles cross several grouping cells (3 index cells of 0.2 = 0.6 wide) on the
    // way in. Every step must still see every particle within r_e of every vertex: the result
    // is the direct sum over all particles, in double precision, iteration by iteration.
    std::vector<openvdb::Vec3f> particles;
    uint32_t state = 12345u;
    const auto jitter = [&] {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) / float(1u << 24) - 0.5f;  // [-0.5, 0.5)
    };
    for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j)
            for (int k = 0; k < 6; ++k) {
                // In sequence, z first (GCC's argument order, which the data were made with):
                // an argument list's order is unspecified, and other compilers drew another block.
                const float jz = jitter(), jy = jitter(), jx = jitter();
                particles.push_back(openvdb::Vec3f(0.3f * (float(i) + 0.3f * jx), 0.3f * (float(j) + 0.3f * jy),
                                                   0.3f * (float(k) + 0.3f * jz)));
            }
    const double radius = 1.0;
    SurfaceMesh mesh;
    for (int n = 0; n < 3000; ++n) {  // around the block, most within r_e of some particle
        const float jz = jitter(), jy = jitter(), jx = jitter();  // as above
        mesh.points.push_back(openvdb::Vec3s(0.75f + 3.8f * jx, 0.75f + 3.8f * jy, 0.75f + 3.8f * jz));
    }
    std::vector<openvdb::Vec3d> expected(mesh.points.begin(), mesh.points.end());
    const int iterations = 3;
    for (int t = 0; t < iterations; ++t) {
        for (openvdb::Vec3d& v : expected) {
            double weightSum = 0.0;
            openvdb::Vec3d weighted(0.0);
            for (const openvdb::Vec3f& p : particles) {
                const double d = (openvdb::Vec3d(p) - v).length();
                if (d >= radius) continue;
                const double w = radius / std::max(d, double(kMinDistanceFraction) * radius) - 1.0;
                weightSum += w;
                weighted += w * openvdb::Vec3d(p);
            }
            if (weightSum > 0.0) v = weighted / weightSum;
        }
    }
    const std::vector<openvdb::Vec3s> start = mesh.points;
    relaxVertices(mesh, ParticleIndex::build(particles, 0.2), relaxSettings(1.0, iterations));
    size_t farTravellers = 0;
    for (size_t i = 0; i < mesh.points.size(); ++i) {
        ASSERT_NEAR((openvdb::Vec3d(mesh.points[i]) - expected[i]).length(), 0.0, 1e-5) << "vertex " << i;
        farTravellers += (mesh.points[i] - start[i]).length() > 0.6f;
    }
    EXPECT_GT(farTravellers, 500u);  // the case this test is about did occur
}

TEST(RelaxVertices, AStopLeavesEachVertexWhereItWasOrFullyRelaxed)
{
    // Groups of vertices take all their steps at once and are written back whole, so a stop
    // partway leaves a mix of untouched and finished vertices, never one between the two.
    std::vector<openvdb::Vec3f> particles;
    for (int i = 0; i < 2000; ++i) particles.push_back(openvdb::Vec3f(0.3f * float(i), 0.0f, 0.0f));
    uint32_t state = 777u;
    const auto jitter = [&] {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) / float(1u << 24) - 0.5f;  // [-0.5, 0.5)
    };
    SurfaceMesh start;
    for (int n = 0; n < 20000; ++n) {
        // In sequence, z first (GCC's argument order, which the data were made with).
        const float jz = jitter(), jy = jitter(), jx = jitter();
        start.points.push_back(openvdb::Vec3s(600.0f * (jx + 0.5f), 1.2f * jy, 1.2f * jz));
    }
    const ParticleIndex index = ParticleIndex::build(particles, 0.5);
    SurfaceMesh relaxed = start;
    relaxVertices(relaxed, index, relaxSettings(0.3, 2));

    /// Says stop once 30% of the work is reported done, ever after.
    struct StopAtThirtyPercent : openvdb::util::NullInterrupter
    {
        bool wasInterrupted(int percent = -1) override
        {
            if (percent >= 30) fired = true;
            return fired.load();
        }
        std::atomic<bool> fired{false};
    } interrupter;
    SurfaceMesh stopped = start;
    EXPECT_THROW(relaxVertices(stopped, index, relaxSettings(0.3, 2), &interrupter), CancelledError);
    size_t untouched = 0, finished = 0;
    for (size_t i = 0; i < start.points.size(); ++i) {
        const bool isStart = stopped.points[i] == start.points[i];
        const bool isRelaxed = stopped.points[i] == relaxed.points[i];
        ASSERT_TRUE(isStart || isRelaxed) << "vertex " << i;
        untouched += isStart && !isRelaxed;
        finished += isRelaxed && !isStart;
    }
    EXPECT_GT(untouched, 0u);  // the stop did come partway
    EXPECT_GT(finished, 0u);
}

TEST(RelaxVertices, StopsWithinTheStepsOfOneGroup)
{
    // Each vertex group takes all its steps before the next group starts: with t = 2³⁰, a
    // stop must be heard between the steps of one group, not only between groups.
    // The stop comes after twice the polls of a whole run at t = 1: beyond any poll before
    // the steps or between groups.
    OneParticle one;
    struct StopAfterPolls : openvdb::util::NullInterrupter
    {
        explicit StopAfterPolls(long n) : limit(n) {}
        bool wasInterrupted(int = -1) override { return ++polls >= limit && limit > 0; }
        long limit;
        std::atomic<long> polls{0};
    };
    StopAfterPolls counter(0);
    SurfaceMesh mesh = one.mesh;
    relaxVertices(mesh, one.index, relaxSettings(0.3, 1), &counter);
    StopAfterPolls stop(2 * counter.polls + 10);
    mesh = one.mesh;
    try {
        relaxVertices(mesh, one.index, relaxSettings(0.3, 1 << 30), &stop);
        ADD_FAILURE() << "not stopped";
    } catch (const CancelledError& e) {
        EXPECT_STREQ(e.what(), "interrupted during relax vertices");
    }
    EXPECT_GE(stop.polls, stop.limit);
}

TEST(RelaxVertices, RejectsBadSettings)
{
    OneParticle one;
    const auto expectMessage = [&](const RelaxSettings& settings, const char* message) {
        try {
            relaxVertices(one.mesh, one.index, settings);
            ADD_FAILURE() << "accepted: " << message;
        } catch (const ParameterError& e) {
            EXPECT_STREQ(e.what(), message);
        }
    };
    expectMessage(relaxSettings(1.5, 2), "--blend must lie in [0,1], got 1.5");
    expectMessage(relaxSettings(-0.1, 2), "--blend must lie in [0,1], got -0.1");
    expectMessage(relaxSettings(0.3, -1), "--iterations must be >= 0, got -1");
    RelaxSettings noRadius = relaxSettings(0.3, 2);
    noRadius.effectiveRadius = 0.0;
    expectMessage(noRadius, "--radius must be > 0, got 0");
    noRadius.effectiveRadius = -std::numeric_limits<double>::infinity();
    expectMessage(noRadius, "--radius must be finite, got -inf");
    noRadius.effectiveRadius = 2e18;  // r_e² overflows single precision
    expectMessage(noRadius, "--radius 2e+18 is too large: at most 1e+18 (lengths are squared in single precision); "
                            "give the positions in a larger unit");
    RelaxSettings badCap = relaxSettings(0.3, 2);
    badCap.maxStep = -1.0;
    expectMessage(badCap, "--max-step must be >= 0 (0 or inf: no cap), got -1");
    badCap.maxStep = std::nan("");
    expectMessage(badCap, "--max-step must be >= 0 (0 or inf: no cap), got nan");
}

TEST(RelaxVertices, AnInfiniteStepCapIsNoCap)
{
    // It was refused as "--max-step must be >= 0, got inf" (bug hunt).
    OneParticle uncapped, infinite;
    RelaxSettings settings = relaxSettings(0.5, 2);
    relaxVertices(uncapped.mesh, uncapped.index, settings);
    settings.maxStep = std::numeric_limits<double>::infinity();
    relaxVertices(infinite.mesh, infinite.index, settings);
    EXPECT_EQ(infinite.mesh.points, uncapped.mesh.points);
}

TEST(RelaxVertices, VerticesThatAreNotFiniteStayPutAndTheOthersRelaxAsWithoutThem)
{
    // A host application's mesh may carry a NaN, an infinite or a far-flung vertex; the
    // grouping bounds the vertices' cells by their box, and must neither take them in nor
    // hang on them (a NaN vertex took 30 s before they were left out of every group).
    OneParticle one;
    SurfaceMesh expected = one.mesh;
    relaxVertices(expected, one.index, relaxSettings(0.3, 2));
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const std::vector<openvdb::Vec3s> bad = {{nan, 0.0f, 0.0f}, {inf, 1.0f, 2.0f}, {0.0f, -inf, nan}, {1e30f, 0.0f, 0.0f}};
    for (const openvdb::Vec3s& vertex : bad) {
        SurfaceMesh mesh = one.mesh;
        mesh.points.insert(mesh.points.begin() + mesh.points.size() / 2, vertex);
        relaxVertices(mesh, one.index, relaxSettings(0.3, 2));
        ASSERT_EQ(mesh.points.size(), expected.points.size() + 1);
        const size_t at = expected.points.size() / 2;
        for (size_t i = 0; i < expected.points.size(); ++i) {
            ASSERT_EQ(mesh.points[i < at ? i : i + 1], expected.points[i]) << "vertex " << i;
        }
        const openvdb::Vec3s kept = mesh.points[at];
        for (int a = 0; a < 3; ++a) {
            EXPECT_TRUE(std::isnan(vertex[a]) ? std::isnan(kept[a]) : kept[a] == vertex[a]) << "axis " << a;
        }
    }
}

TEST(RelaxVertices, AnIndexWhoseCellsAreFarFromTheRadiusIsRefusedHereAndByRasterize)
{
    // Cells of 1e-4 for r_e = 0.2 (a unit mistake) made a relaxation of minutes that no
    // interrupter could stop: a search box probed 16 million cell columns.
    OneParticle one;
    DensitySettings density;
    density.effectiveRadius = 1.0;
    density.voxelSize = 0.1;
    const RelaxSettings relax = relaxSettings(0.3, 2);
    const auto expectRefused = [&](double cellSize, const std::string& message) {
        SCOPED_TRACE(cellSize);
        const ParticleIndex index = ParticleIndex::build({kCentre}, cellSize);
        SurfaceMesh mesh = one.mesh;
        EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { relaxVertices(mesh, index, relax); }), message);
        EXPECT_EQ(mesh.points, one.mesh.points);
        EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { rasterizeDensity(index, density); }), message);
    };
    expectRefused(0.01, "particle index cells of 0.01 are too small for --radius 1: at most 8 cells per radius "
                        "(build the index with cells of r_e/2, 0.5)");
    expectRefused(5.0, "particle index cells of 5 are too large for --radius 1: at least 0.25 cells per radius "
                       "(build the index with cells of r_e/2, 0.5)");

    // The bounds themselves are accepted, and give the same vertices as cells of r_e/2.
    SurfaceMesh expected = one.mesh;
    relaxVertices(expected, one.index, relax);
    for (const double cellSize : {1.0 / kMaxCellsPerRadius, 1.0 / kMinCellsPerRadius}) {
        SCOPED_TRACE(cellSize);
        const ParticleIndex index = ParticleIndex::build({kCentre}, cellSize);
        SurfaceMesh mesh = one.mesh;
        relaxVertices(mesh, index, relax);
        EXPECT_EQ(mesh.points, expected.points);
        EXPECT_GT(rasterizeDensity(index, density)->activeVoxelCount(), 0u);
    }
    // An index without particles finds nothing whatever its cells: it passes.
    SurfaceMesh mesh = one.mesh;
    relaxVertices(mesh, ParticleIndex::build({}, 0.001), relax);
    EXPECT_EQ(mesh.points, one.mesh.points);
}
