// SPDX-License-Identifier: Apache-2.0
#include "TestUtil.h"

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/Particles.h>
#include <nonbloppy/SurfaceReconstructor.h>

#include <gtest/gtest.h>

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
    const double spacing = reconstructor.reconstruct(ParticleSet{dense, {}}).parameters.spacing;
    EXPECT_NEAR(spacing, 0.1, 0.005 * 0.1);
    EXPECT_EQ(reconstructor.reconstruct(ParticleSet{sparse, {}}).parameters.spacing, spacing);
    reconstructor.setKeepParameters(false);
    EXPECT_NEAR(reconstructor.reconstruct(ParticleSet{sparse, {}}).parameters.spacing, 0.2, 0.005 * 0.2);
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
        EXPECT_THROW(reconstructor.reconstruct(ParticleSet{dense, {}}, &stop), CancelledError);
        const SurfaceResult& next = reconstructor.reconstruct(ParticleSet{sparse, {}});
        EXPECT_NEAR(next.parameters.spacing, 0.2, 0.005 * 0.2);
        SurfaceReconstructor fresh;
        fresh.setKeepParameters(true);
        expectSameMesh(next.mesh, fresh.reconstruct(ParticleSet{sparse, {}}).mesh);
    }
}

TEST(SurfaceReconstructor, CancelledFrameLeavesItUsable)
{
    const auto frame = ballFrame(0.6, 3);
    SurfaceReconstructor reconstructor;
    StopAlways stop;
    EXPECT_THROW(reconstructor.reconstruct(ParticleSet{frame, {}}, &stop), CancelledError);
    const SurfaceResult expected = buildSurface(frame);
    expectSameMesh(reconstructor.reconstruct(ParticleSet{frame, {}}).mesh, expected.mesh);
}

TEST(SurfaceReconstructor, BadParametersThrowParameterError)
{
    SurfaceParameters params;
    params.blend = 2.0;
    SurfaceReconstructor reconstructor(params);
    EXPECT_THROW(reconstructor.reconstruct(ParticleSet{ballFrame(0.5, 1), {}}), ParameterError);
}
