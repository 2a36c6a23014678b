// SPDX-License-Identifier: Apache-2.0
/// @file test_ExtractByRegion.cc
/// @brief Region-by-region extraction (src/SurfaceStages.h, extractByRegion): the very
///        vertices and polygons of a whole-grid volumeToMesh, stitched exactly at every seam,
///        the same order at any thread count, and a cancel checked between regions.

#include "TestUtil.h"

#include "../src/SurfaceStages.h"

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/ExtractSurface.h>
#include <nonbloppy/ParticleIndex.h>
#include <nonbloppy/RasterizeDensity.h>
#include <nonbloppy/ReadParticles.h>

#include <openvdb/util/NullInterrupter.h>
#include <tbb/task_arena.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <map>
#include <string>
#include <vector>

using namespace nonbloppy;
using surface_stages_internal::extractByRegion;
using nonbloppy_test::messageOf;

namespace {

constexpr double kVoxelSize = 0.025, kRadius = 0.1, kThreshold = 6.666;

/// The density of the real dam-break frame (24,389 particles, 1,000-odd leaves).
openvdb::FloatGrid::Ptr damBreakDensityAt(double voxelSize)
{
    const ParticleSet frame =
        readParticles(std::string(NONBLOPPY_TEST_DATA_DIR) + "/dam_break_frame_23_24389_particles.vtk");
    const ParticleIndex index = ParticleIndex::build(frame.positions, kRadius / 2);
    DensitySettings settings;
    settings.effectiveRadius = kRadius;
    settings.voxelSize = voxelSize;
    return rasterizeDensity(index, settings);
}

const openvdb::FloatGrid& damBreakDensity()
{
    static const openvdb::FloatGrid::Ptr grid = damBreakDensityAt(kVoxelSize);
    return *grid;
}

using Quad = std::array<std::array<float, 3>, 4>;

/// Every quad as its four vertex positions, rotated to start at the smallest one (so the
/// winding is kept), sorted: equal for two meshes with the same polygons in any order.
std::vector<Quad> canonicalQuads(const SurfaceMesh& mesh)
{
    std::vector<Quad> quads;
    quads.reserve(mesh.quads.size());
    for (const openvdb::Vec4I& q : mesh.quads) {
        Quad corners;
        for (int i = 0; i < 4; ++i) {
            for (int k = 0; k < 3; ++k) corners[i][k] = mesh.points[q[i]][k];
        }
        const int start = int(std::min_element(corners.begin(), corners.end()) - corners.begin());
        Quad rotated;
        for (int i = 0; i < 4; ++i) rotated[i] = corners[(start + i) % 4];
        quads.push_back(rotated);
    }
    std::sort(quads.begin(), quads.end());
    return quads;
}

/// Stops at its @a stopAt-th question and counts the questions.
class CountingInterrupter : public openvdb::util::NullInterrupter
{
public:
    explicit CountingInterrupter(int stopAt) : mStopAt(stopAt) {}
    // Atomic: extraction asks from its pipeline's parallel filter too, and CancelPoll asks
    // interrupters from many tasks at once (Cancellation.h).
    bool wasInterrupted(int = -1) override { return ++mQuestions >= mStopAt; }
    int questions() const { return mQuestions.load(); }
private:
    int mStopAt;
    std::atomic<int> mQuestions{0};
};

} // namespace

TEST(ExtractByRegion, GivesTheVerticesAndPolygonsOfTheWholeGridAtEveryRegionSize)
{
    const SurfaceMesh whole = extractSurface(damBreakDensity(), kThreshold);
    ASSERT_GT(whole.quads.size(), 30000u);
    const std::vector<Quad> expected = canonicalQuads(whole);
    // 1 kept leaf and 1 layer per region make a seam at every leaf layer; 100000 one region.
    for (const size_t leavesPerRegion : {size_t(1), size_t(8), size_t(100), size_t(100000)}) {
        SurfaceMesh regions;
        extractByRegion(damBreakDensity(), kThreshold, regions, nullptr, leavesPerRegion, 1);
        EXPECT_EQ(regions.points.size(), whole.points.size()) << leavesPerRegion << " leaves per region";
        EXPECT_TRUE(regions.triangles.empty());
        EXPECT_TRUE(canonicalQuads(regions) == expected) << leavesPerRegion << " leaves per region";
        // No vertex twice: a seam vertex welded into one.
        std::vector<std::array<float, 3>> points;
        for (const openvdb::Vec3s& p : regions.points) points.push_back({p[0], p[1], p[2]});
        std::sort(points.begin(), points.end());
        EXPECT_TRUE(std::adjacent_find(points.begin(), points.end()) == points.end());
    }
}

TEST(ExtractByRegion, GivesTheWholeGridsMeshAtTheDefaultLeastThickness)
{
    // kMinLayersPerRegion (12) leaf layers per cut: the frame at h = 0.025 spans fewer than
    // two such slabs, so this grid is four times finer (about 70 leaf layers).
    const openvdb::FloatGrid::Ptr fine = damBreakDensityAt(kVoxelSize / 4);
    const SurfaceMesh whole = extractSurface(*fine, kThreshold);
    SurfaceMesh regions;
    extractByRegion(*fine, kThreshold, regions, nullptr, 8);
    ASSERT_EQ(regions.points.size(), whole.points.size());
    EXPECT_FALSE(regions.points == whole.points);  // meshed by region: another order
    EXPECT_TRUE(canonicalQuads(regions) == canonicalQuads(whole));
}

TEST(ExtractByRegion, ResolvesAmbiguousFacesAtASeamAsTheWholeGridDoes)
{
    // Noise around the iso-value makes ambiguous faces everywhere. volumeToMesh resolves a
    // cell's ambiguous face from the signs of the cell beyond it, so a claimed cell two
    // voxels outside a slab reads a third plane of the shell: with two planes, seams lose
    // quads (it did on the 64x benchmark input, 5 to 10 of 6.6 M).
    // Two boxes: slabs along x cut into bands along y, and slabs along z cut into bands
    // along x, so that the shell of a region is cut on every axis.
    for (const openvdb::Coord& size : {openvdb::Coord(64, 16, 16), openvdb::Coord(24, 16, 64)}) {
        openvdb::FloatGrid::Ptr noise = openvdb::FloatGrid::create(0.0f);
        noise->setTransform(openvdb::math::Transform::createLinearTransform(kVoxelSize));
        uint32_t state = 12345u;  // a fixed linear congruential sequence: the same field everywhere
        auto accessor = noise->getAccessor();
        for (int i = 0; i < size[0]; ++i)
            for (int j = 0; j < size[1]; ++j)
                for (int k = 0; k < size[2]; ++k) {
                    state = state * 1664525u + 1013904223u;
                    accessor.setValue(openvdb::Coord(i, j, k), 2.0f * float(state >> 8) / float(1u << 24));
                }
        const std::vector<Quad> expected = canonicalQuads(extractSurface(*noise, 1.0));
        ASSERT_GT(expected.size(), 10000u);
        for (const size_t leavesPerRegion : {size_t(1), size_t(8)}) {
            SurfaceMesh regions;
            extractByRegion(*noise, 1.0, regions, nullptr, leavesPerRegion, 1);
            EXPECT_TRUE(canonicalQuads(regions) == expected) << size << ", " << leavesPerRegion << " leaves per region";
        }
    }
}

TEST(ExtractByRegion, GivesTheWholeGridsVertexBitsOnATranslatedGrid)
{
    // Each region's grid took transform.copy(), and OpenVDB rebuilds a translated map from
    // its matrix: this grid's UniformScaleTranslateMap came back a ScaleTranslateMap whose x
    // scale is 0.025000000000005684, so the regions placed vertices a few double steps off
    // the whole grid's, and one float step off where that crossed a rounding boundary: 289 of
    // these 706 vertices (differential hunt, random grids translated out to 1e6). The
    // library's own grids have no translation (rasterizeDensity() takes a UniformScaleMap
    // only, whose copy is exact); extractByRegion() accepts translated ones.
    openvdb::FloatGrid::Ptr slab = openvdb::FloatGrid::create(0.0f);
    openvdb::math::Transform::Ptr transform = openvdb::math::Transform::createLinearTransform(kVoxelSize);
    transform->postTranslate(openvdb::Vec3d(100.0, 0.0, 0.0));
    slab->setTransform(transform);
    // A slab three voxels thick, 16 x 16 (four regions of one leaf), its crossings at dyadic
    // fractions of a voxel.
    const float past = 9.0f / 16384.0f;
    auto accessor = slab->getAccessor();
    for (int j = 0; j < 16; ++j)
        for (int k = 0; k < 16; ++k) {
            for (int i = 0; i <= 2; ++i) accessor.setValue(openvdb::Coord(i, j, k), 1.0f + past);
            accessor.setValue(openvdb::Coord(3, j, k), past);
        }
    const SurfaceMesh whole = extractSurface(*slab, 1.0);
    ASSERT_GT(whole.quads.size(), 500u);
    SurfaceMesh regions;
    extractByRegion(*slab, 1.0, regions, nullptr, 1, 1);
    ASSERT_EQ(regions.points.size(), whole.points.size());
    EXPECT_FALSE(regions.points == whole.points);  // meshed by region: another order
    EXPECT_TRUE(canonicalQuads(regions) == canonicalQuads(whole));
}

TEST(ExtractByRegion, LeavesOutAndTilesLeavesNoCrossingTouchesWithoutChangingTheMesh)
{
    // A solid block of particles: a deep interior (tiles after tileDeepInterior(), "above"
    // leaves in every region) and a thick outer fringe below r_0 (left out).
    std::vector<openvdb::Vec3f> block;
    for (int i = 0; i < 48; ++i)
        for (int j = 0; j < 40; ++j)
            for (int k = 0; k < 32; ++k)
                block.emplace_back(0.05f * float(i), 0.05f * float(j), 0.05f * float(k));
    const ParticleIndex index = ParticleIndex::build(block, kRadius / 2);
    DensitySettings settings;
    settings.effectiveRadius = kRadius;
    settings.voxelSize = kVoxelSize;
    const openvdb::FloatGrid::Ptr density = rasterizeDensity(index, settings);
    const std::vector<Quad> expected = canonicalQuads(extractSurface(*density, kThreshold));
    ASSERT_GT(expected.size(), 10000u);
    SurfaceMesh regions;
    extractByRegion(*density, kThreshold, regions, nullptr, 16, 1);
    EXPECT_TRUE(canonicalQuads(regions) == expected);

    openvdb::FloatGrid::Ptr tiled = density->deepCopy();
    ASSERT_GT(tileDeepInterior(*tiled, kThreshold), 0u);
    extractByRegion(*tiled, kThreshold, regions, nullptr, 16, 1);
    EXPECT_TRUE(canonicalQuads(regions) == expected);
}

TEST(ExtractByRegion, RegionLeavesOfBuildSurfaceChangesOnlyTheOrder)
{
    // SurfaceParameters::regionLeaves: 0 meshes the grid whole, any other value by region;
    // the plain method without relaxation leaves the extracted mesh as it is.
    const ParticleSet frame =
        readParticles(std::string(NONBLOPPY_TEST_DATA_DIR) + "/dam_break_frame_23_24389_particles.vtk");
    SurfaceParameters params;
    params.effectiveRadius = kRadius;
    params.voxelSize = kVoxelSize;
    params.threshold = kThreshold;
    params.iterations = 0;
    params.method = Method::Paper;
    std::vector<Quad> expected;
    for (const size_t regionLeaves : {size_t(0), size_t(1), size_t(64), kDefaultRegionLeaves}) {
        params.regionLeaves = regionLeaves;
        const SurfaceResult result = buildSurface(frame.positions, params);
        EXPECT_EQ(result.parameters.regionLeaves, regionLeaves);
        if (regionLeaves == 0) {
            expected = canonicalQuads(result.mesh);
            ASSERT_GT(expected.size(), 30000u);
        } else {
            EXPECT_TRUE(canonicalQuads(result.mesh) == expected) << regionLeaves << " leaves per region";
        }
    }
}

TEST(ExtractByRegion, SameOrderAtOneTwoAndThreeThreads)
{
    // Regions are meshed a batch of one per thread at a time: batches of 1, 2 and 3 (which
    // leaves a short last batch) must weld into the same mesh.
    SurfaceMesh one, two, three;
    tbb::task_arena(1).execute([&] { extractByRegion(damBreakDensity(), kThreshold, one, nullptr, 64, 1); });
    tbb::task_arena(2).execute([&] { extractByRegion(damBreakDensity(), kThreshold, two, nullptr, 64, 1); });
    tbb::task_arena(3).execute([&] { extractByRegion(damBreakDensity(), kThreshold, three, nullptr, 64, 1); });
    ASSERT_EQ(one.points.size(), two.points.size());
    EXPECT_TRUE(one.points == two.points);
    EXPECT_TRUE(one.quads == two.quads);
    EXPECT_TRUE(one.points == three.points);
    EXPECT_TRUE(one.quads == three.quads);
}

TEST(ExtractByRegion, AsksTheInterrupterBetweenRegionsAndStops)
{
    CountingInterrupter never(1 << 30);
    SurfaceMesh mesh;
    extractByRegion(damBreakDensity(), kThreshold, mesh, &never, 50, 1);
    // Once before the work and once before each region: the frame's 400-odd leaves that a
    // crossing touches make eight regions of 50 or more (a region ends on a whole layer).
    EXPECT_GE(never.questions(), 9);

    // On one thread: with two, a second thread could ask once more between the third
    // answer and the stop being recorded.
    CountingInterrupter third(3);
    tbb::task_arena oneThread(1);
    EXPECT_EQ(messageOf<CancelledError>([&] {
        oneThread.execute([&] { extractByRegion(damBreakDensity(), kThreshold, mesh, &third, 50, 1); });
    }), "interrupted during extract surface");
    EXPECT_EQ(third.questions(), 3);
}

TEST(ExtractByRegion, RejectsANonFiniteThreshold)
{
    SurfaceMesh mesh;
    EXPECT_EQ(messageOf<ParameterError>([&] {
        extractByRegion(damBreakDensity(), std::nan(""), mesh, nullptr, 100);
    }), "--threshold must be finite, got nan");
}

TEST(ExtractByRegion, ReleasingTheGridGivesTheSameMeshBitForBit)
{
    // A grid meshed for the last time gives its leaves back slab by slab (the CLI without
    // --vdb): the same vertices and polygons in the same order, and far fewer leaves left.
    for (const size_t leavesPerRegion : {size_t(1), size_t(8), size_t(64)}) {
        SurfaceMesh kept;
        extractByRegion(damBreakDensity(), kThreshold, kept, nullptr, leavesPerRegion, 1);
        openvdb::FloatGrid::Ptr copy = damBreakDensity().deepCopy();
        const openvdb::Index64 leavesBefore = copy->tree().leafCount();
        SurfaceMesh released;
        extractByRegion(*copy, kThreshold, released, nullptr, leavesPerRegion, 1, &copy->tree());
        EXPECT_EQ(released.points, kept.points) << leavesPerRegion;
        EXPECT_EQ(released.quads, kept.quads) << leavesPerRegion;
        EXPECT_EQ(released.normals, kept.normals) << leavesPerRegion;
        EXPECT_LT(copy->tree().leafCount(), leavesBefore / 2) << leavesPerRegion;
    }
    // The whole stage chain: the same mesh with and without the grid kept.
    SurfaceParameters params;
    params.spacing = 0.05;
    const ParticleSet frame =
        readParticles(std::string(NONBLOPPY_TEST_DATA_DIR) + "/dam_break_frame_23_24389_particles.vtk");
    const SurfaceResult withGrid = buildSurface(frame.positions, params);
    params.keepDensity = false;
    const SurfaceResult without = buildSurface(frame.positions, params);
    ASSERT_TRUE(withGrid.density);
    EXPECT_FALSE(without.density);
    EXPECT_EQ(without.mesh.points, withGrid.mesh.points);
    EXPECT_EQ(without.mesh.quads, withGrid.mesh.quads);
}

namespace {

/// Counts the stages an interrupter is told of, by name.
class StageCounter : public openvdb::util::NullInterrupter
{
public:
    void start(const char* name) override { if (name) ++mStarts[name]; }
    int starts(const std::string& name) const
    {
        const auto it = mStarts.find(name);
        return it == mStarts.end() ? 0 : it->second;
    }

private:
    std::map<std::string, int> mStarts;
};

/// Whether every edge of @a mesh's quads has exactly two quads and no quad repeats a vertex.
bool closedAndManifold(const SurfaceMesh& mesh)
{
    std::map<std::pair<uint32_t, uint32_t>, int> edges;
    for (const openvdb::Vec4I& q : mesh.quads) {
        for (int k = 0; k < 4; ++k) {
            for (int m = k + 1; m < 4; ++m) {
                if (q[k] == q[m]) return false;
            }
            const uint32_t a = q[k], b = q[(k + 1) % 4];
            ++edges[{std::min(a, b), std::max(a, b)}];
        }
    }
    for (const auto& [edge, count] : edges) {
        if (count != 2) return false;
    }
    return !edges.empty();
}

} // namespace

TEST(ExtractByRegion, SeamVerticesThatShareAPositionAreNotWelded)
{
    // Cells whose crossings fall on a shared voxel corner or face put distinct vertices on
    // one point. Welding seams by position joined them, and the seam's quads collapsed into
    // triangles with a repeated corner (differential hunt). Such seams are meshed with the
    // whole grid instead: from the grid as it is, or again from the particles when its
    // leaves were being freed (keepDensity false) and some are gone.
    const auto expectWholeGridsMesh = [](const std::vector<openvdb::Vec3f>& positions, SurfaceParameters params,
                                         size_t regionLeaves, int rasterizingsWhenFreed, const char* what) {
        params.iterations = 0;
        params.regionLeaves = 0;
        const SurfaceResult whole = buildSurface(positions, params);
        ASSERT_TRUE(closedAndManifold(whole.mesh)) << what;
        for (const bool keepDensity : {true, false}) {
            params.regionLeaves = regionLeaves;
            params.keepDensity = keepDensity;
            StageCounter stages;
            const SurfaceResult byRegion = buildSurface(positions, params, &stages);
            EXPECT_TRUE(closedAndManifold(byRegion.mesh)) << what << ", keepDensity " << keepDensity;
            EXPECT_EQ(byRegion.mesh.points, whole.mesh.points) << what << ", keepDensity " << keepDensity;
            EXPECT_EQ(byRegion.mesh.quads, whole.mesh.quads) << what << ", keepDensity " << keepDensity;
            const int rasterizings = keepDensity ? 1 : rasterizingsWhenFreed;
            EXPECT_EQ(stages.starts("rasterize density"), rasterizings) << what << ", keepDensity " << keepDensity;
            EXPECT_EQ(stages.starts("extract surface"), rasterizings) << what << ", keepDensity " << keepDensity;
        }
    };
    // A particle halfway between voxel planes 183 and 184, the second seam of regions one
    // leaf each (slabs of 12 leaf layers from -8): both planes get density exactly 3, every
    // crossing beside them lands on a voxel, and four cells share each vertex position.
    // The first seam's leaves are freed by then.
    SurfaceParameters exact;
    exact.effectiveRadius = 1.0;
    exact.voxelSize = 0.5;
    exact.threshold = 3.0;
    expectWholeGridsMesh({openvdb::Vec3f(0.0f), openvdb::Vec3f(91.75f, 0.0f, 0.0f)}, exact, 1, 2, "exact density");

    // Far from the origin a float's step nears a tenth of a voxel, and crossings round onto
    // voxel faces: a jittered box 3e4 out was not closed at --region-leaves 64 (the dam
    // break 1e4 out neither).
    std::vector<openvdb::Vec3f> box;
    uint32_t state = 2024u;
    const auto jitter = [&] {
        state = state * 1664525u + 1013904223u;
        return (float(state >> 8) / float(1u << 24) - 0.5f) * 0.15f;  // ±0.075
    };
    for (int i = 0; i < 200; ++i)
        for (int j = 0; j < 20; ++j)
            for (int k = 0; k < 20; ++k) {
                // Drawn in sequence, z first (as GCC evaluated the arguments this box was found
                // with): an argument list's order is unspecified, and clang's left-to-right
                // order made another box, with no ambiguous seam to fall back on.
                const float jz = jitter(), jy = jitter(), jx = jitter();
                box.emplace_back(3.0e4f + 0.25f * (float(i) + jx), 3.0e4f + 0.25f * (float(j) + jy),
                                 3.0e4f + 0.25f * (float(k) + jz));
            }
    expectWholeGridsMesh(box, SurfaceParameters(), 64, 2, "box 3e4 out");
}
