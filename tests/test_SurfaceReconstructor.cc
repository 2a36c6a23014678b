// SPDX-License-Identifier: Apache-2.0
#include "TestUtil.h"

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/Particles.h>
#include <nonbloppy/RasterizeDensity.h>
#include <nonbloppy/RelaxVertices.h>
#include <nonbloppy/SurfaceReconstructor.h>

#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

using namespace nonbloppy;
using nonbloppy_test::latticeParticles;

namespace {

void expectSameMesh(const SurfaceMesh& a, const SurfaceMesh& b)
{
    ASSERT_EQ(a.points.size(), b.points.size());
    ASSERT_EQ(a.triangles.size(), b.triangles.size());
    ASSERT_EQ(a.quads.size(), b.quads.size());
    ASSERT_EQ(a.normals.size(), b.normals.size());
    for (size_t i = 0; i < a.points.size(); ++i) ASSERT_EQ(a.points[i], b.points[i]) << i;
    for (size_t i = 0; i < a.quads.size(); ++i) ASSERT_EQ(a.quads[i], b.quads[i]) << i;
    for (size_t i = 0; i < a.triangles.size(); ++i) ASSERT_EQ(a.triangles[i], b.triangles[i]) << i;
    for (size_t i = 0; i < a.normals.size(); ++i) ASSERT_EQ(a.normals[i], b.normals[i]) << i;
}

std::vector<openvdb::Vec3f> ballFrame(double radius, unsigned seed)
{
    return latticeParticles(0.1, radius + 0.1,
        [radius](const openvdb::Vec3d& x) { return x.length() < radius; }, 0.1, seed);
}

struct StopAlways : openvdb::util::NullInterrupter
{
    bool wasInterrupted(int = -1) override { return true; }
};

/// Says stop from the start of the stage @a stage on.
struct StopInStage : openvdb::util::NullInterrupter
{
    explicit StopInStage(std::string stage) : stage(std::move(stage)) {}
    void start(const char* name) override { stopping = stopping || (name && stage == name); }
    bool wasInterrupted(int = -1) override { return stopping; }
    std::string stage;
    bool stopping = false;
};

/// A ParticleList whose getPos() throws at one particle, as a caller's cache reader may.
struct ThrowingParticles
{
    const std::vector<openvdb::Vec3f>* positions;
    size_t failAt;
    size_t size() const { return positions->size(); }
    void getPos(size_t n, openvdb::Vec3R& xyz) const
    {
        if (n == failAt) throw std::runtime_error("cache read failed");
        xyz = (*positions)[n];
    }
};

} // namespace

TEST(SurfaceReconstructor, EqualsBuildSurfaceFrameAfterFrame)
{
    SurfaceReconstructor reconstructor;
    // Growing, shrinking and growing again: buffers are reused at every size.
    for (double radius : {0.6, 0.9, 0.5, 0.8}) {
        const auto frame = ballFrame(radius, unsigned(radius * 10));
        const SurfaceResult expected = buildSurface(frame);
        const SurfaceResult& got = reconstructor.reconstruct(PositionArrayView<float>(frame.data()->asPointer(), frame.size()));
        SCOPED_TRACE(radius);
        EXPECT_EQ(got.particleCount, frame.size());
        EXPECT_EQ(got.parameters.effectiveRadius, expected.parameters.effectiveRadius);
        EXPECT_EQ(got.density->activeVoxelCount(), expected.density->activeVoxelCount());
        expectSameMesh(got.mesh, expected.mesh);
        EXPECT_EQ(reconstructor.particleIndex().size(), frame.size());
    }
    EXPECT_EQ(reconstructor.frameCount(), 4u);
}

TEST(SurfaceReconstructor, KeepsTheFirstFramesParametersWhenAsked)
{
    const auto dense = latticeParticles(0.1, 0.7, [](const openvdb::Vec3d& x) { return x.length() < 0.6; });
    const auto sparse = latticeParticles(0.2, 0.7, [](const openvdb::Vec3d& x) { return x.length() < 0.6; });
    SurfaceReconstructor reconstructor;
    reconstructor.setKeepParameters(true);
    const double spacing = reconstructor.reconstruct(ParticleSet{dense, {}, {}}).parameters.spacing;
    EXPECT_NEAR(spacing, 0.1, 0.005 * 0.1);
    EXPECT_EQ(reconstructor.reconstruct(ParticleSet{sparse, {}, {}}).parameters.spacing, spacing);
    reconstructor.setKeepParameters(false);
    EXPECT_NEAR(reconstructor.reconstruct(ParticleSet{sparse, {}, {}}).parameters.spacing, 0.2, 0.005 * 0.2);
}

TEST(SurfaceReconstructor, NewParametersForgetTheKeptOnes)
{
    // Kept from a dense frame (s = 0.1) with c = 0.5, then replaced by the defaults: the
    // sparser frame's spacing (0.2) is estimated again, and the mesh is the one a fresh
    // reconstructor with the defaults makes, bit for bit.
    const auto dense = latticeParticles(0.1, 0.7, [](const openvdb::Vec3d& x) { return x.length() < 0.6; });
    const auto sparse = latticeParticles(0.2, 0.7, [](const openvdb::Vec3d& x) { return x.length() < 0.6; });
    SurfaceParameters strong;
    strong.blend = 0.5;
    SurfaceReconstructor reconstructor(strong);
    reconstructor.setKeepParameters(true);
    EXPECT_NEAR(reconstructor.reconstruct(ParticleSet{dense, {}, {}}).parameters.spacing, 0.1, 0.005 * 0.1);
    reconstructor.setParameters(SurfaceParameters());
    EXPECT_EQ(reconstructor.parameters().blend, SurfaceParameters().blend);
    EXPECT_TRUE(reconstructor.keepParameters());  // only the kept values are forgotten
    const SurfaceResult& next = reconstructor.reconstruct(ParticleSet{sparse, {}, {}});
    EXPECT_NEAR(next.parameters.spacing, 0.2, 0.005 * 0.2);
    SurfaceReconstructor fresh;
    fresh.setKeepParameters(true);
    const SurfaceResult& expected = fresh.reconstruct(ParticleSet{sparse, {}, {}});
    EXPECT_EQ(next.parameters.spacing, expected.parameters.spacing);
    EXPECT_EQ(next.parameters.effectiveRadius, expected.parameters.effectiveRadius);
    EXPECT_EQ(next.parameters.threshold, expected.parameters.threshold);
    EXPECT_EQ(next.parameters.voxelSize, expected.parameters.voxelSize);
    expectSameMesh(next.mesh, expected.mesh);
    // And the new parameters are kept in turn: a dense frame now keeps the sparse spacing.
    EXPECT_EQ(reconstructor.reconstruct(ParticleSet{dense, {}, {}}).parameters.spacing, next.parameters.spacing);
}

TEST(SurfaceReconstructor, AFrameWithoutParticlesIsRefusedKeptParametersOrNot)
{
    // With kept parameters nothing was resolved to refuse it: an empty mesh, or with the
    // spacing given "target volume must be > 0, got 0" from the volume correction.
    const auto ball = latticeParticles(0.1, 0.7, [](const openvdb::Vec3d& x) { return x.length() < 0.6; });
    SurfaceParameters params;
    params.spacing = 0.1;
    for (const bool keep : {false, true}) {
        SurfaceReconstructor reconstructor(params);
        reconstructor.setKeepParameters(keep);
        const size_t vertices = reconstructor.reconstruct(ParticleSet{ball, {}, {}}).mesh.points.size();
        EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { reconstructor.reconstruct(ParticleSet{}); }),
                  "no particles to mesh")
            << "keep " << keep;
        EXPECT_EQ(reconstructor.reconstruct(ParticleSet{ball, {}, {}}).mesh.points.size(), vertices);
    }
}

TEST(SurfaceReconstructor, AFrameThatFailsKeepsNoParameters)
{
    // The parameters were kept as soon as they were resolved: a frame stopped later (or
    // throwing later) left them for the next frame, which then differed from a fresh object's.
    const auto dense = latticeParticles(0.1, 0.7, [](const openvdb::Vec3d& x) { return x.length() < 0.6; });
    const auto sparse = latticeParticles(0.2, 0.7, [](const openvdb::Vec3d& x) { return x.length() < 0.6; });
    for (const char* stage : {"rasterize density", "relax vertices", "compute normals"}) {
        SCOPED_TRACE(stage);
        SurfaceReconstructor reconstructor;
        reconstructor.setKeepParameters(true);
        StopInStage stop(stage);
        EXPECT_THROW(reconstructor.reconstruct(ParticleSet{dense, {}, {}}, &stop), CancelledError);
        const SurfaceResult& next = reconstructor.reconstruct(ParticleSet{sparse, {}, {}});
        EXPECT_NEAR(next.parameters.spacing, 0.2, 0.005 * 0.2);
        SurfaceReconstructor fresh;
        fresh.setKeepParameters(true);
        expectSameMesh(next.mesh, fresh.reconstruct(ParticleSet{sparse, {}, {}}).mesh);
    }
}

TEST(SurfaceReconstructor, CancelledFrameLeavesItUsable)
{
    const auto frame = ballFrame(0.6, 3);
    SurfaceReconstructor reconstructor;
    StopAlways stop;
    EXPECT_THROW(reconstructor.reconstruct(ParticleSet{frame, {}, {}}, &stop), CancelledError);
    const SurfaceResult expected = buildSurface(frame);
    expectSameMesh(reconstructor.reconstruct(ParticleSet{frame, {}, {}}).mesh, expected.mesh);
}

TEST(SurfaceReconstructor, BadParametersThrowParameterError)
{
    SurfaceParameters params;
    params.blend = 2.0;
    SurfaceReconstructor reconstructor(params);
    const ParticleSet frame{ballFrame(0.5, 1), {}, {}};
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { reconstructor.reconstruct(frame); }),
              "--blend must lie in [0,1], got 2");
}

TEST(SurfaceReconstructor, AFrameThatThrowsLeavesAnEmptyUsableIndex)
{
    // A failed frame used to leave particleIndex() with the old grid but without its
    // positions (their storage had been recycled for the new frame): relaxing a mesh
    // against it read out of bounds. Every way of failing now leaves an empty index.
    const auto small = ballFrame(0.5, 1);
    const auto large = ballFrame(0.9, 2);  // more particles: the position buffer is recycled
    auto withNaN = large;
    withNaN[7][1] = std::numeric_limits<float>::quiet_NaN();
    const auto nanFrame = [&](SurfaceReconstructor& r) { r.reconstruct(ParticleSet{withNaN, {}, {}}); };
    const auto stoppedFrame = [&](SurfaceReconstructor& r) {
        StopInStage stop("relax vertices");
        r.reconstruct(ParticleSet{large, {}, {}}, &stop);
    };
    const auto readerFails = [&](SurfaceReconstructor& r) { r.reconstruct(ThrowingParticles{&large, 11}); };
    const std::vector<std::function<void(SurfaceReconstructor&)>> failures{nanFrame, stoppedFrame, readerFails};
    const std::vector<std::string> messages{"non-finite position of particle 7",
                                            "interrupted during relax vertices", "cache read failed"};
    for (size_t k = 0; k < failures.size(); ++k) {
        SCOPED_TRACE(messages[k]);
        SurfaceReconstructor reconstructor;
        const SurfaceResult& first = reconstructor.reconstruct(ParticleSet{small, {}, {}});
        ASSERT_EQ(reconstructor.particleIndex().size(), small.size());
        SurfaceMesh probe = first.mesh;
        try {
            failures[k](reconstructor);
            FAIL() << "no exception";
        } catch (const std::exception& error) {
            EXPECT_EQ(std::string(error.what()), messages[k]);
        }
        EXPECT_EQ(reconstructor.particleIndex().size(), 0u);
        EXPECT_EQ(reconstructor.particleIndex().sortedPositions().size(), 0u);

        // Relaxing against an empty index leaves the vertices where they are.
        RelaxSettings relax;
        relax.effectiveRadius = 0.25;
        const std::vector<openvdb::Vec3s> before = probe.points;
        relaxVertices(probe, reconstructor.particleIndex(), relax);
        EXPECT_EQ(probe.points, before);
        DensitySettings density;
        density.effectiveRadius = 0.25;
        density.voxelSize = 0.05;
        EXPECT_EQ(rasterizeDensity(reconstructor.particleIndex(), density)->activeVoxelCount(), 0u);

        // And the next frame is a fresh object's.
        const SurfaceResult& next = reconstructor.reconstruct(ParticleSet{large, {}, {}});
        EXPECT_EQ(reconstructor.particleIndex().size(), large.size());
        SurfaceReconstructor fresh;
        expectSameMesh(next.mesh, fresh.reconstruct(ParticleSet{large, {}, {}}).mesh);
    }
}
