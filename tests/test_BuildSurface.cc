// SPDX-License-Identifier: Apache-2.0
#include "TestUtil.h"

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/CorrectSurface.h>
#include <nonbloppy/ExtractSurface.h>
#include <nonbloppy/InterpolateAttributes.h>
#include <nonbloppy/MeasureMesh.h>
#include <nonbloppy/ReadParticles.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <thread>
#include <vector>

using namespace nonbloppy;
using nonbloppy_test::dataPath;
using nonbloppy_test::latticeParticles;

TEST(BuildSurface, NormalsPointOutOfABallOfParticles)
{
    const auto ball = latticeParticles(0.1, 1.1, [](const openvdb::Vec3d& x) { return x.length() < 1.0; }, 0.1);
    const SurfaceResult result = buildSurface(ball);
    openvdb::BBoxd box;  // the particles' own box
    for (const openvdb::Vec3f& p : ball) box.expand(openvdb::Vec3d(p));
    EXPECT_EQ(result.particleBounds, box);
    ASSERT_FALSE(box.empty());
    const SurfaceMesh& mesh = result.mesh;
    ASSERT_EQ(mesh.normals.size(), mesh.points.size());
    ASSERT_GT(mesh.points.size(), 1000u);
    for (size_t i = 0; i < mesh.points.size(); ++i) {
        EXPECT_NEAR(mesh.normals[i].length(), 1.0f, 1e-5f);
        ASSERT_GT(mesh.normals[i].dot(mesh.points[i]), 0.0f) << "vertex " << i;
    }
    const MeshMeasures measures = measureMesh(mesh);
    EXPECT_TRUE(measures.closed);
    EXPECT_TRUE(measures.manifold);
    EXPECT_GT(measures.volume, 0.0);
}

TEST(BuildSurface, CallerArraysModelTheParticleListConcept)
{
    // A caller's own packed double array, viewed without copying.
    const std::vector<double> xyz{0.0, 0.0, 0.0};
    SurfaceParameters params;
    params.effectiveRadius = 1.0;
    params.threshold = 1.0;
    params.voxelSize = 0.05;
    params.blend = 0.5;
    params.iterations = 1;
    const SurfaceResult result = buildSurface(PositionArrayView<double>(xyz.data(), 1), params);
    EXPECT_EQ(result.particleCount, 1u);
    EXPECT_EQ(result.particleBounds, openvdb::BBoxd(openvdb::Vec3d(0.0), openvdb::Vec3d(0.0)));
    EXPECT_FALSE(result.parameters.spacingGiven);
    EXPECT_EQ(result.parameters.spacing, 0.0);  // not needed: every length was given
    ASSERT_GT(result.mesh.points.size(), 200u);  // a sphere of radius 0.5 at h = 0.05, relaxed to 0.25
    for (const openvdb::Vec3s& p : result.mesh.points) {
        ASSERT_NEAR(p.length(), 0.5 * 0.5, 0.05 / 4 * 0.5 + 1e-6);
    }
    // The grid carries the parameters.
    EXPECT_EQ(result.density->metaValue<double>("effective_radius"), 1.0);
    EXPECT_EQ(result.density->metaValue<int32_t>("iterations"), 1);
    EXPECT_EQ(result.density->metaValue<int64_t>("particle_count"), 1);
}

TEST(BuildSurface, DamBreakFrameIsClosedManifoldAndOutward)
{
    const ParticleSet particles = readParticles(dataPath("dam_break_frame_23_24389_particles.vtk"));
    ASSERT_EQ(particles.size(), 24389u);
    const SurfaceResult result = buildSurface(particles);
    // SPlisHSPlasH particle radius 0.025, volume 0.8·(2r)³ per particle: s = 0.0464 (the
    // median nearest-neighbour distance is 0.0393).
    EXPECT_NEAR(result.parameters.spacing, 0.0464, 0.0008);
    const MeshMeasures measures = measureMesh(result.mesh);
    // Each particle stands for s³ of fluid: the mesh holds N·s³, measured +0.9% (splashes
    // included; no volume correction runs with an estimated spacing).
    EXPECT_NEAR(measures.volume / (24389.0 * std::pow(result.parameters.spacing, 3)), 1.0, 0.03);
    EXPECT_GT(measures.polygons, 10000u);
    EXPECT_TRUE(measures.closed);
    EXPECT_TRUE(measures.manifold);
    EXPECT_EQ(measures.unusedVertices, 0u);
    EXPECT_GT(measures.volume, 0.0);
}

TEST(BuildSurface, TheVolumeCorrectionAndSmoothingTurnFewTrianglesOver)
{
    // Both move vertices along their normals: slivers between neighbours moved by different
    // amounts turned over, 4,404 of the 108,200 triangles (bug hunt). Each is now checked
    // against the surface it started from: 382 are left facing against the relaxed surface.
    const ParticleSet particles = readParticles(dataPath("dam_break_frame_23_24389_particles.vtk"));
    SurfaceParameters params;
    params.spacing = 0.0467;
    const SurfaceResult corrected = buildSurface(particles, params);
    params.preserveVolume = false;
    params.smoothSurface = false;
    const SurfaceResult relaxed = buildSurface(particles, params);
    ASSERT_EQ(corrected.mesh.triangles, relaxed.mesh.triangles);
    ASSERT_EQ(corrected.mesh.quads, relaxed.mesh.quads);
    const size_t triangles = corrected.mesh.triangles.size() + 2 * corrected.mesh.quads.size();
    EXPECT_GT(triangles, 100000u);
    EXPECT_LT(countFoldedTriangles(corrected.mesh, relaxed.mesh.points), triangles / 200);
    // The volume still moves towards N·s³: relaxed +1.0%, corrected +0.5% (+0.4% before the
    // repair, which leaves the reverted vertices unoffset; smoothing takes the rest).
    const double target = 24389.0 * std::pow(0.0467, 3);
    EXPECT_LT(std::abs(measureAreaAndVolume(corrected.mesh).volume - target),
              0.75 * std::abs(measureAreaAndVolume(relaxed.mesh).volume - target));
}

TEST(BuildSurface, IdenticalWithOneAndTwoThreads)
{
    const ParticleSet particles = readParticles(dataPath("double_dam_break_frame_26_4732_particles.vtk"));
    SurfaceResult serial, parallel;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        serial = buildSurface(particles);
    }
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
        parallel = buildSurface(particles);
    }
    ASSERT_GT(serial.mesh.points.size(), 0u);
    EXPECT_EQ(serial.mesh.points, parallel.mesh.points);
    EXPECT_EQ(serial.mesh.normals, parallel.mesh.normals);
    EXPECT_EQ(serial.mesh.quads, parallel.mesh.quads);
    EXPECT_EQ(serial.mesh.triangles, parallel.mesh.triangles);
    EXPECT_EQ(serial.density->activeVoxelCount(), parallel.density->activeVoxelCount());
}

TEST(BuildSurface, IdenticalWithOneAndSevenThreads)
{
    // A farm node runs 32 or 64 threads, the suite's machines two: the other tests compare one
    // thread with two, which would pass for work split in two pieces whatever the threads
    // (the tasks' count then depending on the thread count beyond two). Here seven threads on
    // however many cores, an odd count that splits no range as one or two threads do, through
    // every stage: the spacing given (volume correction and smoothing), the density kept, and
    // the particles' id and velocity interpolated onto the vertices.
    const ParticleSet particles = readParticles(dataPath("dam_break_frame_23_24389_particles.vtk"));
    SurfaceParameters params;
    params.spacing = 0.0467;
    params.regionLeaves = 64;  // several extraction regions, which the pipeline runs at once
    const auto run = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        tbb::task_arena arena(threads);
        SurfaceResult result;
        arena.execute([&] {
            EXPECT_EQ(tbb::this_task_arena::max_concurrency(), threads);
            result = buildSurface(particles, params);
            interpolateAttributes(result.mesh, particles, {"all"}, result.parameters.effectiveRadius);
        });
        return result;
    };
    const SurfaceResult serial = run(1);
    const SurfaceResult parallel = run(7);
    ASSERT_GT(serial.mesh.points.size(), 10000u);
    EXPECT_EQ(serial.mesh.points, parallel.mesh.points);
    EXPECT_EQ(serial.mesh.normals, parallel.mesh.normals);
    EXPECT_EQ(serial.mesh.quads, parallel.mesh.quads);
    EXPECT_EQ(serial.mesh.triangles, parallel.mesh.triangles);
    ASSERT_EQ(serial.mesh.attributes.size(), 2u);
    ASSERT_EQ(parallel.mesh.attributes.size(), 2u);
    for (size_t a = 0; a < 2; ++a) {
        EXPECT_EQ(serial.mesh.attributes[a].name, parallel.mesh.attributes[a].name);
        EXPECT_EQ(serial.mesh.attributes[a].values, parallel.mesh.attributes[a].values) << serial.mesh.attributes[a].name;
        EXPECT_EQ(serial.mesh.attributes[a].integers, parallel.mesh.attributes[a].integers) << serial.mesh.attributes[a].name;
    }
    // The density grid, leaf by leaf: the same leaves, values and active voxels.
    ASSERT_TRUE(serial.density && parallel.density);
    EXPECT_EQ(serial.density->tree().leafCount(), parallel.density->tree().leafCount());
    auto other = parallel.density->tree().cbeginLeaf();
    for (auto leaf = serial.density->tree().cbeginLeaf(); leaf; ++leaf, ++other) {
        ASSERT_TRUE(other) << "fewer leaves with seven threads";
        ASSERT_EQ(leaf->origin(), other->origin());
        ASSERT_TRUE(leaf->getValueMask() == other->getValueMask()) << leaf->origin();
        ASSERT_TRUE(std::equal(leaf->buffer().data(), leaf->buffer().data() + leaf->SIZE, other->buffer().data(),
                               [](float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }))
            << leaf->origin();
    }
}

TEST(BuildSurface, TheSameBytesWhateverTheParticlesOrder)
{
    // Particles of one cell were summed in file order: the same frame written in another
    // order (a simulator that re-sorts its particles, a conversion) estimated s = 0.0467139,
    // 0.0467137 or 0.0467175 and meshed to other bytes. The index now orders each cell's
    // particles by position. Checked with the spacing estimated, and given (the volume
    // correction and the smoothing then run too).
    const ParticleSet particles = readParticles(dataPath("dam_break_frame_23_24389_particles.vtk"));
    std::vector<openvdb::Vec3f> shuffled = particles.positions;
    std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(11));
    std::vector<openvdb::Vec3f> reversed(particles.positions.rbegin(), particles.positions.rend());
    for (const double spacing : {0.0, 0.0467}) {
        SurfaceParameters params;
        if (spacing > 0.0) params.spacing = spacing;
        const SurfaceResult inOrder = buildSurface(particles.positions, params);
        ASSERT_GT(inOrder.mesh.points.size(), 10000u);
        for (const std::vector<openvdb::Vec3f>* other : {&shuffled, &reversed}) {
            const SurfaceResult result = buildSurface(*other, params);
            EXPECT_EQ(result.parameters.spacing, inOrder.parameters.spacing) << spacing;
            EXPECT_TRUE(result.mesh.points == inOrder.mesh.points) << spacing;
            EXPECT_TRUE(result.mesh.normals == inOrder.mesh.normals) << spacing;
            EXPECT_EQ(result.mesh.triangles, inOrder.mesh.triangles) << spacing;
            EXPECT_EQ(result.mesh.quads, inOrder.mesh.quads) << spacing;
        }
    }
}

TEST(BuildSurface, ConcurrentCallsOnDifferentFramesGiveTheirOwnResults)
{
    // The header's promise to a studio meshing several frames from its own threads: each
    // call's result is the one it gets alone (no shared state), whichever finishes first.
    const std::vector<std::string> names = {"double_dam_break_frame_26_4732_particles.vtk",
                                            "bunny_frame_14_7705_particles.vtk", "cube_2366_particles.vtk"};
    std::vector<ParticleSet> frames;
    std::vector<SurfaceMesh> alone;
    SurfaceParameters params;
    params.keepDensity = false;  // the region-by-region release path too
    for (const std::string& name : names) {
        frames.push_back(readParticles(dataPath(name)));
        alone.push_back(buildSurface(frames.back(), params).mesh);
        ASSERT_GT(alone.back().points.size(), 1000u) << name;
    }
    std::vector<SurfaceMesh> together(names.size());
    std::vector<std::string> errors(names.size());
    {
        std::vector<std::thread> threads;
        for (size_t f = 0; f < names.size(); ++f) {
            threads.emplace_back([&, f] {
                try {
                    for (int round = 0; round < 2; ++round) together[f] = buildSurface(frames[f], params).mesh;
                } catch (const std::exception& e) {
                    errors[f] = e.what();
                }
            });
        }
        for (std::thread& t : threads) t.join();
    }
    for (size_t f = 0; f < names.size(); ++f) {
        EXPECT_EQ(errors[f], "") << names[f];
        EXPECT_TRUE(together[f].points == alone[f].points) << names[f];
        EXPECT_TRUE(together[f].normals == alone[f].normals) << names[f];
        EXPECT_TRUE(together[f].quads == alone[f].quads && together[f].triangles == alone[f].triangles) << names[f];
    }
}

TEST(BuildSurface, DroppingTheDensityTilesTheInteriorAndKeepsTheMeshBitForBit)
{
    const ParticleSet particles = readParticles(dataPath("dam_break_frame_23_24389_particles.vtk"));
    SurfaceParameters params;
    const SurfaceResult exact = buildSurface(particles, params);
    params.keepDensity = false;
    const SurfaceResult tiled = buildSurface(particles, params);
    EXPECT_FALSE(tiled.density);
    EXPECT_EQ(exact.mesh.points, tiled.mesh.points);
    EXPECT_EQ(exact.mesh.quads, tiled.mesh.quads);
    EXPECT_EQ(exact.mesh.triangles, tiled.mesh.triangles);
    EXPECT_EQ(exact.mesh.normals, tiled.mesh.normals);
}

TEST(ExtractSurface, DeepInteriorLeavesBecomeTilesAndTheSurfaceStaysTheSame)
{
    // A ball 36 spacings across (9 leaves) has leaves deep inside.
    const auto ball = latticeParticles(0.1, 1.9, [](const openvdb::Vec3d& x) { return x.length() < 1.8; });
    SurfaceParameters params;
    params.iterations = 0;
    const SurfaceResult result = buildSurface(ball, params);
    const openvdb::FloatGrid::Ptr tiled = result.density->deepCopy();
    const size_t leavesBefore = tiled->tree().leafCount();
    const size_t replaced = tileDeepInterior(*tiled, result.parameters.threshold);
    EXPECT_GT(replaced, 0u);
    EXPECT_EQ(tiled->tree().leafCount(), leavesBefore - replaced);
    // Tiles hold a value above r_0 (inside), so the surface is the same.
    const SurfaceMesh mesh = extractSurface(*tiled, result.parameters.threshold);
    EXPECT_EQ(mesh.points, result.mesh.points);
    EXPECT_EQ(mesh.quads, result.mesh.quads);
}
