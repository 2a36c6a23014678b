// SPDX-License-Identifier: Apache-2.0
// Tests of diagnoseSurface(): each condition on a real pipeline run that shows it, and a
// run that shows none.

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/DiagnoseSurface.h>
#include <nonbloppy/InterpolateAttributes.h>
#include <nonbloppy/ReadParticles.h>

#include "TestUtil.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace nonbloppy;

namespace {

const std::string kFreeParticles = std::string(NONBLOPPY_TEST_DATA_DIR) + "/free_particles_125_particles.vtk";
const std::string kCube = std::string(NONBLOPPY_TEST_DATA_DIR) + "/cube_2366_particles.vtk";

/// The paper's method on one particle: r_e = 1, r_0 = 1, h = 0.05 (a sphere of radius 0.5).
SurfaceParameters oneParticleParameters()
{
    SurfaceParameters params;
    params.method = Method::Paper;
    params.effectiveRadius = 1.0;
    params.threshold = 1.0;
    params.voxelSize = 0.05;
    params.iterations = 0;
    return params;
}

} // namespace

TEST(DiagnoseSurface, ARealFrameMeshedAsAskedShowsNothing)
{
    ParticleSet particles = readParticles(kCube);
    SurfaceResult result = buildSurface(particles);
    interpolateAttributes(result.mesh, particles, {"all"}, result.parameters.effectiveRadius);
    const SurfaceDiagnostics d = diagnoseSurface(result);
    EXPECT_FALSE(d.facesEndInside);
    EXPECT_FALSE(d.empty);
    EXPECT_FALSE(d.coarseFloats());
    EXPECT_EQ(d.verticesWithoutNormal, 0u);
    EXPECT_TRUE(d.nonFiniteAttributes.empty());
    // The float step at the particles' farthest coordinate, as std::nextafter gives it.
    const float farthest = float(d.farthestCoordinate);
    EXPECT_EQ(d.floatStep, double(std::nextafter(farthest, 1e30f)) - double(farthest));
    EXPECT_EQ(d.floatStepLimit, result.parameters.spacing / 16.0);
}

TEST(DiagnoseSurface, AThresholdNoSampleReachesLeavesAnEmptyMesh)
{
    SurfaceParameters params = oneParticleParameters();
    params.threshold = 1e30;  // within float's range, far above any sample
    const SurfaceResult result = buildSurface(std::vector<openvdb::Vec3f>{{0.3f, 0.1f, 0.2f}}, params);
    EXPECT_TRUE(result.mesh.points.empty());
    EXPECT_TRUE(diagnoseSurface(result).empty);
}

TEST(DiagnoseSurface, ParticlesFarFromTheOriginHaveCoarseFloats)
{
    // At 2^20 floats step by 2^-3 = 0.125: 2.5 voxels of 0.05, 20 times h/8 (no spacing
    // known: r_e, r_0 and h given), enough for droplets to vanish.
    const float far = float(1 << 20);
    const SurfaceResult result = buildSurface(std::vector<openvdb::Vec3f>{{far, 0.0f, 0.0f}}, oneParticleParameters());
    const SurfaceDiagnostics d = diagnoseSurface(result);
    EXPECT_EQ(d.farthestCoordinate, double(far));
    EXPECT_EQ(d.floatStep, 0.125);
    EXPECT_EQ(d.floatStepLimit, 0.05 / 8.0);
    EXPECT_TRUE(d.coarseFloats());
    EXPECT_TRUE(d.dropletsMayVanish());
    // At 2^10 the step (2^-13) is below the limit.
    const SurfaceResult near = buildSurface(std::vector<openvdb::Vec3f>{{1024.0f, 0.0f, 0.0f}}, oneParticleParameters());
    EXPECT_FALSE(diagnoseSurface(near).coarseFloats());
}

TEST(DiagnoseSurface, FullBlendCollapsesDropletsToVerticesWithoutNormals)
{
    // c = 1 moves a lone particle's sphere onto the particle: every vertex to the weighted
    // mean of that one particle, (w r) / w, which rounds to r itself for most of them; the
    // faces whose corners all land on r have no area, and their vertices no normal.
    SurfaceParameters params = oneParticleParameters();
    params.blend = 1.0;
    params.iterations = 1;
    const SurfaceResult result = buildSurface(std::vector<openvdb::Vec3f>{{0.3f, 0.1f, 0.2f}}, params);
    ASSERT_FALSE(result.mesh.points.empty());
    size_t zero = 0;
    for (const openvdb::Vec3s& n : result.mesh.normals) zero += n == openvdb::Vec3s(0.0f);
    EXPECT_GT(zero, result.mesh.points.size() / 4);
    EXPECT_EQ(diagnoseSurface(result).verticesWithoutNormal, zero);
    // Half the blend: every face keeps its area.
    params.blend = 0.5;
    EXPECT_EQ(diagnoseSurface(buildSurface(std::vector<openvdb::Vec3f>{{0.3f, 0.1f, 0.2f}}, params)).verticesWithoutNormal, 0u);
}

TEST(DiagnoseSurface, StrongRelaxationEndsFacesInside)
{
    SurfaceParameters params;
    params.blend = 0.4;
    params.iterations = 3;
    const SurfaceResult result = buildSurface(readParticles(kCube), params);
    EXPECT_FALSE(result.parameters.thresholdReachesSurface);
    EXPECT_TRUE(diagnoseSurface(result).facesEndInside);
}

TEST(DiagnoseSurface, CountsVerticesWithANonFiniteAttributePerAttribute)
{
    ParticleSet particles = readParticles(kFreeParticles);
    std::vector<float> temperature(particles.size(), 300.0f), pressure(particles.size(), 1.0f);
    temperature[7] = std::numeric_limits<float>::quiet_NaN();
    particles.attributes = {ParticleAttribute::of("temperature", 1, temperature),
                            ParticleAttribute::of("pressure", 1, pressure)};
    SurfaceResult result = buildSurface(particles);
    interpolateAttributes(result.mesh, particles, {"all"}, result.parameters.effectiveRadius);
    // The vertices within r_e of particle 7, counted directly.
    const openvdb::Vec3f centre = particles.positions[7];
    size_t near = 0;
    for (const openvdb::Vec3s& v : result.mesh.points) near += (v - centre).length() < result.parameters.effectiveRadius;
    ASSERT_GT(near, 0u);
    const SurfaceDiagnostics d = diagnoseSurface(result);
    ASSERT_EQ(d.nonFiniteAttributes.size(), 1u);
    EXPECT_EQ(d.nonFiniteAttributes[0].first, "temperature");
    EXPECT_EQ(d.nonFiniteAttributes[0].second, near);
}
