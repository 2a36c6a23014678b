// SPDX-License-Identifier: Apache-2.0
// Surface fidelity (issue 4): small versions of the shapes of the fidelity benchmark
// (tests/bench/fidelity.cc, docs/fidelity.md) with its targets, and the corrections of
// CorrectSurface.h one by one.

#include "TestUtil.h"
#include "bench/FidelityShapes.h"

#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/ComputeNormals.h>
#include <nonbloppy/CorrectSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/ExtractSurface.h>
#include <nonbloppy/MeasureMesh.h>
#include <nonbloppy/ParticleIndex.h>
#include <nonbloppy/RasterizeDensity.h>
#include <nonbloppy/RelaxVertices.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

using namespace nonbloppy;
using namespace nonbloppy_fidelity;

namespace {

/// Every method of the benchmark meshes at voxel size s/2 and is given the spacing.
SurfaceMesh meshShape(const Shape& shape, SurfaceParameters params = SurfaceParameters())
{
    params.spacing = shape.spacing;
    params.voxelSize = 0.5 * shape.spacing;
    return buildSurface(shape.particles, params).mesh;
}

SurfaceMesh blobs(const Shape& shape)
{
    SurfaceParameters params;
    params.method = Method::Paper;
    params.iterations = 0;
    return meshShape(shape, params);
}

/// The targets, in units of s, with the loosening a small shape needs.
struct Targets
{
    double mean = 0.10, p95 = 0.25, truthP95 = 0.30, volume = 0.03;
};

void expectTargets(const Shape& shape, const Targets& targets, double blobRatio)
{
    const Fidelity f = measureFidelity(meshShape(shape), shape);
    const Fidelity b = measureFidelity(blobs(shape), shape);
    SCOPED_TRACE(shape.name + " (" + shape.description + ")");
    EXPECT_LE(f.meanDistance, targets.mean);
    EXPECT_LE(f.p95Distance, targets.p95);
    EXPECT_LE(f.truthP95, targets.truthP95);
    EXPECT_LE(std::abs(f.volumeError), targets.volume);
    EXPECT_TRUE(f.closed);
    EXPECT_TRUE(f.manifold);
    // Closer than blobs by at least this factor (the benchmark's sizes show the real margin).
    EXPECT_LE(f.meanDistance * blobRatio, b.meanDistance) << "blobs: " << b.meanDistance;
}

} // namespace

// ------------------------------------------------------------------------------------------
// The shapes at small sizes (`nonbloppy_fidelity --small` prints their full table), with the
// issue's targets. Smaller shapes have more of their area in edges and corners, where every
// particle method rounds; the loosening is stated per shape from the values measured at these
// sizes (docs/fidelity.md has the full sizes, which meet the absolute targets unloosened).
// The "2× closer than blobs" is held unloosened; the measured margins are in the
// comments (docs/fidelity.md has the full sizes: 2.3–5.2×).

TEST(Fidelity, SmallBox)
{
    // 8³ instead of 16³, unloosened: measured mean 0.025, truth p95 0.083, 3.0× closer than
    // blobs (2.3× at 16³; without smoothSurface() 1.73×).
    expectTargets(makeBox(8), Targets(), 2.0);
}

TEST(Fidelity, SmallSlabTwoParticlesThick)
{
    // 12×12 instead of 24×24, unloosened: measured mean 0.021, truth p95 0.089, 3.8× closer
    // than blobs (2.5× at 24²; without smoothSurface() 1.95×).
    expectTargets(makeSlab(12), Targets(), 2.0);
}

TEST(Fidelity, SmallBall)
{
    // Unloosened; measured mean 0.031, 3.1× closer than blobs (2.3× at radius 8.5 s; without
    // smoothSurface() 1.12×: relaxation follows the staircase of the lattice ball, which
    // the normal filter smooths since its steps turn the normal by far less than 90°).
    expectTargets(makeBall(4.5), Targets(), 2.0);
}

TEST(Fidelity, SmallJetThreeParticlesAcross)
{
    // Unloosened; measured mean 0.029, truth p95 0.106, 4.1× closer than blobs.
    expectTargets(makeJet(14), Targets(), 2.0);
}

TEST(Fidelity, SmoothingIsWhatBringsTheBallTwiceAsClose)
{
    // The same ball without smoothSurface() (measured 0.085 against 0.031).
    const Shape ball = makeBall(4.5);
    SurfaceParameters params;
    params.smoothSurface = false;
    const double unsmoothed = measureFidelity(meshShape(ball, params), ball).meanDistance;
    const double smoothed = measureFidelity(meshShape(ball), ball).meanDistance;
    EXPECT_GT(unsmoothed, 1.8 * smoothed) << unsmoothed << " vs " << smoothed;
}

// ------------------------------------------------------------------------------------------
// Method::Paper is the paper's plain pipeline, bit for bit.

TEST(Fidelity, PaperMethodIsThePlainPipeline)
{
    const Shape ball = makeBall(3.5, 0.1);
    SurfaceParameters params;
    params.method = Method::Paper;
    params.spacing = 0.1;
    const SurfaceResult result = buildSurface(ball.particles, params);
    EXPECT_DOUBLE_EQ(result.parameters.threshold, calibrateThreshold(2.0));
    EXPECT_EQ(result.parameters.maxStep, 0.0);
    EXPECT_FALSE(result.parameters.preserveVolume);
    EXPECT_FALSE(result.parameters.repairFolds);
    EXPECT_FALSE(result.parameters.smoothSurface);

    const ParticleIndex index = ParticleIndex::build(ball.particles, 0.5 * 0.2);
    DensitySettings density;
    density.effectiveRadius = 0.2;
    density.voxelSize = 0.05;
    SurfaceMesh mesh = extractSurface(*rasterizeDensity(index, density), calibrateThreshold(2.0));
    RelaxSettings relax;
    relax.effectiveRadius = 0.2;
    relax.blend = kDefaultBlend;
    relax.iterations = kDefaultIterations;
    relaxVertices(mesh, index, relax);
    ASSERT_GT(mesh.points.size(), 500u);
    ASSERT_EQ(mesh.points.size(), result.mesh.points.size());
    for (size_t i = 0; i < mesh.points.size(); ++i) ASSERT_EQ(mesh.points[i], result.mesh.points[i]) << i;
    EXPECT_TRUE(mesh.quads == result.mesh.quads && mesh.triangles == result.mesh.triangles);
}

TEST(Fidelity, DefaultsAreIdenticalWithOneAndTwoThreads)
{
    const Shape jet = makeJet(10);
    SurfaceMesh one, two;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = meshShape(jet);
    }
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
        two = meshShape(jet);
    }
    ASSERT_GT(one.points.size(), 500u);
    ASSERT_EQ(one.points.size(), two.points.size());
    for (size_t i = 0; i < one.points.size(); ++i) ASSERT_EQ(one.points[i], two.points[i]) << i;
    EXPECT_TRUE(one.normals == two.normals);
    EXPECT_TRUE(one.quads == two.quads && one.triangles == two.triangles);
}

// ------------------------------------------------------------------------------------------
// The corrections one by one.

TEST(Fidelity, RelaxedThresholdEndsAFlatFaceHalfASpacingOutside)
{
    // As EstimateParameters' blob test, but relaxed (c = 0.3, t = 2), no volume correction
    // (the spacing is estimated): the calibration alone must land the face at s/2.
    const double spacing = 0.1;
    const auto slab = detail::lattice(spacing, 16, [](int i, int j, int k) {
        return std::abs(i) <= 15 && std::abs(j) <= 15 && k <= 0 && k >= -7;
    }, 0.0, 1);
    const SurfaceResult result = buildSurface(slab);
    EXPECT_FALSE(result.parameters.preserveVolume);
    EXPECT_DOUBLE_EQ(result.parameters.threshold,
                     calibrateRelaxedThreshold(2.0, kDefaultBlend, kDefaultIterations));
    const auto [meanHeight, count] = nonbloppy_test::meanTopHeight(result.mesh.points);
    ASSERT_GT(count, 50);
    EXPECT_NEAR(meanHeight, spacing / 2, 0.03 * spacing);
}

TEST(Fidelity, RelaxationThatReachesFromTheStartLimitIsCalibrated)
{
    // c = 0.5, t = 2 relaxes a face that starts at the limit, 1.5 s out, to just past s/2:
    // the scan gave up before trying the limit itself, warned that the faces end inside and
    // fell back to starting there (bug hunt). The face of a slab lands at s/2.
    const double spacing = 0.1;
    const auto slab = detail::lattice(spacing, 16, [](int i, int j, int k) {
        return std::abs(i) <= 15 && std::abs(j) <= 15 && k <= 0 && k >= -7;
    }, 0.0, 1);
    SurfaceParameters params;
    params.blend = 0.5;
    params.iterations = 2;
    const SurfaceResult result = buildSurface(slab, params);
    EXPECT_TRUE(result.parameters.thresholdReachesSurface);
    const auto [meanHeight, count] = nonbloppy_test::meanTopHeight(result.mesh.points);
    ASSERT_GT(count, 50);
    EXPECT_NEAR(meanHeight, spacing / 2, 0.03 * spacing);
    bool reaches = false;
    calibrateRelaxedThreshold(2.0, 0.5, 2, &reaches, kDefaultMaxStepOverSpacing);
    EXPECT_TRUE(reaches);
    calibrateRelaxedThreshold(2.0, 0.5, 3, &reaches, kDefaultMaxStepOverSpacing);  // beyond reach
    EXPECT_FALSE(reaches);
}

TEST(Fidelity, RelaxedThresholdIsTheBlobThresholdWithoutRelaxation)
{
    EXPECT_EQ(calibrateRelaxedThreshold(2.0, 0.3, 0), calibrateThreshold(2.0));
    EXPECT_EQ(calibrateRelaxedThreshold(2.0, 0.0, 3), calibrateThreshold(2.0));
    // Relaxation pulls the surface in, so it must start farther out: a lower iso-value.
    EXPECT_LT(calibrateRelaxedThreshold(2.0, 0.3, 2), calibrateThreshold(2.0));
    EXPECT_LT(calibrateRelaxedThreshold(2.0, 0.3, 3), calibrateRelaxedThreshold(2.0, 0.3, 2));
    EXPECT_GT(calibrateRelaxedThreshold(2.0, 1.0, 10), 0.0);  // limited start height, no throw
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([] { calibrateRelaxedThreshold(0.5, 0.3, 2); }),
              "--radius must exceed half the particle spacing to calibrate --threshold, got 0.5 spacings");
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([] { calibrateRelaxedThreshold(2.0, 1.5, 2); }),
              "--blend must lie in [0,1], got 1.5");
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([] { calibrateRelaxedThreshold(2.0, 0.3, -1); }),
              "--iterations must be >= 0, got -1");
}

TEST(Fidelity, RelaxedThresholdTakesTheStepCapIntoAccount)
{
    // The defaults' steps from their start height (1.05 s out) stay under the cap of s/2...
    EXPECT_EQ(calibrateRelaxedThreshold(2.0, kDefaultBlend, kDefaultIterations, nullptr, kDefaultMaxStepOverSpacing),
              calibrateRelaxedThreshold(2.0, kDefaultBlend, kDefaultIterations));
    // ...but c = 0.4, t = 2 starts 1.4 s out, where capped steps are shorter: the capped
    // calibration must start nearer the particles, at a higher density.
    EXPECT_GT(calibrateRelaxedThreshold(2.0, 0.4, 2, nullptr, 0.5), calibrateRelaxedThreshold(2.0, 0.4, 2));
    try {
        calibrateRelaxedThreshold(2.0, 0.3, 2, nullptr, -1.0);
        ADD_FAILURE() << "no exception";
    } catch (const ParameterError& error) {
        EXPECT_STREQ(error.what(), "--max-step must be >= 0 (0 or inf: no cap), got -1 spacings");
    }
}

TEST(Fidelity, StrongerRelaxationWithTheStepCapStaysCloseOnTheBox)
{
    // r_e = 2 s, c = 0.4, t = 2 with the default cap: calibrated for uncapped steps, the
    // box's faces ended 0.094 s off on average (0.033 s with the defaults); calibrated for
    // the capped ones, 0.042 s. The calibration is under test: without smoothSurface().
    const Shape box = makeBox(16);
    SurfaceParameters params;
    params.blend = 0.4;
    params.iterations = 2;
    params.smoothSurface = false;
    const Fidelity f = measureFidelity(meshShape(box, params), box);
    EXPECT_LT(f.meanDistance, 0.05);
    EXPECT_NEAR(f.volumeError, 0.0, 0.01);
}

TEST(Fidelity, FoldedTrianglesAreFoundAndUnfolded)
{
    // Two triangles sharing the edge 1–2, facing +z; vertex 3 pushed across the edge folds one.
    SurfaceMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
    mesh.triangles = {{0, 1, 2}, {1, 3, 2}};
    const std::vector<openvdb::Vec3s> before = mesh.points;
    EXPECT_EQ(countFoldedTriangles(mesh, before), 0u);
    EXPECT_EQ(repairFolds(mesh, before), 0u);
    EXPECT_EQ(mesh.points, before);  // nothing folded: untouched

    mesh.points[3] = openvdb::Vec3s(-0.2f, -0.2f, 0.0f);
    EXPECT_EQ(countFoldedTriangles(mesh, before), 1u);
    EXPECT_EQ(repairFolds(mesh, before), 1u);
    EXPECT_EQ(countFoldedTriangles(mesh, before), 0u);
    // Vertices of unfolded triangles only: vertex 0 is not in the folded triangle.
    EXPECT_EQ(mesh.points[0], before[0]);
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { repairFolds(mesh, {}); }),
              "fold repair needs the positions before relaxation of all 4 vertices, got 0");
    // A negative round count moved every folded vertex all the way back, as 0 does.
    mesh.points[3] = openvdb::Vec3s(-0.2f, -0.2f, 0.0f);
    const std::vector<openvdb::Vec3s> folded = mesh.points;
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { repairFolds(mesh, before, -5); }),
              "fold repair rounds must be >= 0, got -5");
    EXPECT_EQ(mesh.points, folded);
}

TEST(Fidelity, DeepFoldsTakeSeveralHalvingRounds)
{
    // Vertex 3 pushed far across the edge 1–2 (the line x + y = 1): each round moves it
    // halfway back, x = y: -5 -> -2 -> -0.5 -> 0.25 -> 0.625, and its triangle is folded
    // until the fourth round takes it past the line. Triangle (4, 5, 6) was moved but not
    // folded, and shares no vertex with the fold: it stays as it is, as does vertex 0.
    SurfaceMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {5, 0, 0}, {6, 0, 0}, {5, 1, 0}};
    mesh.triangles = {{0, 1, 2}, {1, 3, 2}, {4, 5, 6}};
    const std::vector<openvdb::Vec3s> before = mesh.points;
    mesh.points[3] = openvdb::Vec3s(-5.0f, -5.0f, 0.0f);
    mesh.points[5] = openvdb::Vec3s(6.0f, 0.5f, 0.0f);
    EXPECT_EQ(countFoldedTriangles(mesh, before), 1u);
    EXPECT_EQ(repairFolds(mesh, before), 1u);
    EXPECT_EQ(countFoldedTriangles(mesh, before), 0u);
    EXPECT_EQ(mesh.points[3], openvdb::Vec3s(0.625f, 0.625f, 0.0f));
    EXPECT_EQ(mesh.points[0], before[0]);
    EXPECT_EQ(mesh.points[5], openvdb::Vec3s(6.0f, 0.5f, 0.0f));
}

TEST(Fidelity, MaxStepCapsEveryRelaxationStep)
{
    // One particle; c = 1 would jump every vertex onto it, the cap stops each at 0.1.
    const std::vector<openvdb::Vec3f> one{openvdb::Vec3f(0.0f)};
    const ParticleIndex index = ParticleIndex::build(one, 0.5);
    DensitySettings density;
    density.effectiveRadius = 1.0;
    density.voxelSize = 0.05;
    SurfaceMesh mesh = extractSurface(*rasterizeDensity(index, density), 1.0);
    ASSERT_GT(mesh.points.size(), 1000u);  // the sphere of radius r_e/(1+r_0) = 0.5
    const std::vector<openvdb::Vec3s> before = mesh.points;
    RelaxSettings relax;
    relax.effectiveRadius = 1.0;
    relax.blend = 1.0;
    relax.iterations = 1;
    relax.maxStep = 0.1;
    relaxVertices(mesh, index, relax);
    for (size_t i = 0; i < mesh.points.size(); ++i) {
        ASSERT_NEAR((mesh.points[i] - before[i]).length(), 0.1f, 1e-5f) << i;
        ASSERT_NEAR(mesh.points[i].length(), before[i].length() - 0.1f, 1e-5f) << i;
    }
    relax.maxStep = -1.0;
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { relaxVertices(mesh, index, relax); }),
              "--max-step must be >= 0 (0 or inf: no cap), got -1");
}

TEST(Fidelity, ConvexVolumeOffsetGrowsEdgesAndLeavesFlatFaces)
{
    // A relaxed box of particles without volume correction: its edges and corners are
    // rounded, its faces flat. The convex offset must give the volume back at the edges.
    const Shape box = makeBox(10, 1.0, 0.0);
    SurfaceParameters params;
    params.preserveVolume = false;
    SurfaceMesh relaxed = meshShape(box, params);
    computeNormals(relaxed);
    const double volume = measureMesh(relaxed).volume;
    const double lo = -5.5, hi = 4.5;  // the true box (makeBox(10): indices -5 … 4, grown by s/2)
    auto edgeDistance = [&](const openvdb::Vec3s& p) {  // to the nearest edge line of the true box
        double q[3];
        for (int a = 0; a < 3; ++a) q[a] = std::min(double(p[a]) - lo, hi - double(p[a]));
        std::sort(q, q + 3);
        return q[1];
    };

    VolumeSettings settings;
    settings.targetVolume = 1.01 * volume;
    settings.convexityFloor = kConvexityFloorOverSpacing;
    settings.maxDistance = 0.5;
    SurfaceMesh convex = relaxed;
    const double farthest = preserveVolume(convex, settings);
    EXPECT_NEAR(measureMesh(convex).volume, settings.targetVolume, 1e-4 * volume);
    EXPECT_GT(farthest, 0.05);
    EXPECT_LE(farthest, 0.5);
    double faceMove = 0.0, edgeMove = 0.0;
    int faceCount = 0, edgeCount = 0;
    for (size_t i = 0; i < relaxed.points.size(); ++i) {
        const double moved = (convex.points[i] - relaxed.points[i]).length();
        if (edgeDistance(relaxed.points[i]) > 2.0) { faceMove = std::max(faceMove, moved); ++faceCount; }
        if (edgeDistance(relaxed.points[i]) < 0.5) { edgeMove += moved; ++edgeCount; }
    }
    ASSERT_GT(faceCount, 100);
    ASSERT_GT(edgeCount, 100);
    EXPECT_LT(faceMove, 1e-6);                  // flat faces stay put
    EXPECT_GT(edgeMove / edgeCount, 0.03);      // edges grow back

    // Uniform moves every vertex the same distance, the faces too.
    settings.offset = VolumeOffset::Uniform;
    SurfaceMesh uniform = relaxed;
    const double distance = preserveVolume(uniform, settings);
    EXPECT_NEAR(measureMesh(uniform).volume, settings.targetVolume, 1e-3 * volume);
    EXPECT_NEAR((uniform.points[0] - relaxed.points[0]).length(), distance, 1e-5);

    // A floor above every convexity leaves no convex vertex: the uniform offset, bit for bit.
    settings.offset = VolumeOffset::Convex;
    settings.convexityFloor = 1e9;
    SurfaceMesh fallback = relaxed;
    EXPECT_EQ(preserveVolume(fallback, settings), distance);
    EXPECT_EQ(fallback.points, uniform.points);
}

TEST(Fidelity, VolumeSettingsAreChecked)
{
    SurfaceMesh mesh = meshShape(makeBox(4));
    auto message = [&](const VolumeSettings& settings) {
        try {
            preserveVolume(mesh, settings);
        } catch (const ParameterError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    VolumeSettings settings;
    settings.targetVolume = 64.0;
    settings.convexityFloor = -1.0;
    EXPECT_EQ(message(settings), "convexity floor must be >= 0, got -1");
    settings.convexityFloor = 0.0;
    settings.maxDistance = 0.0;
    EXPECT_EQ(message(settings), "largest volume offset must be > 0, got 0");
    settings.maxDistance = 1.0;
    settings.targetVolume = 0.0;
    EXPECT_EQ(message(settings), "target volume must be > 0, got 0");
    settings.targetVolume = 64.0;
    // An integer cast to VolumeOffset ran as Convex.
    settings.offset = static_cast<VolumeOffset>(7);
    EXPECT_EQ(message(settings), "volume offset must be Uniform or Convex, got 7");
    settings.offset = VolumeOffset::Convex;
    // The plain overload took a negative limit and moved the surface the wrong way (by -1:
    // inside out); the mesh is left as it was.
    const SurfaceMesh before = mesh;
    for (const double maxDistance : {-0.01, -1.0}) {
        EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { preserveVolume(mesh, 128.0, maxDistance); }),
                  "largest volume offset must be > 0, got " + std::string(maxDistance == -1.0 ? "-1" : "-0.01"));
    }
    EXPECT_EQ(mesh.points, before.points);
    mesh.normals.clear();
    EXPECT_EQ(message(settings), "offsetting a surface needs its normals (computeNormals())");
}

TEST(Fidelity, ConvexVolumeOffsetOnlyWhereTheCalibrationReachesTheSurface)
{
    bool reaches = false;
    calibrateRelaxedThreshold(2.0, kDefaultBlend, kDefaultIterations, &reaches);
    EXPECT_TRUE(reaches);
    calibrateRelaxedThreshold(2.0, 0.5, 4, &reaches);  // would start 2 s out: limited
    EXPECT_FALSE(reaches);

    const Shape jet = makeJet(6);
    SurfaceParameters params;
    params.spacing = 1.0;
    EXPECT_EQ(resolveParameters(params, jet.particles).volumeOffset, VolumeOffset::Convex);
    EXPECT_TRUE(resolveParameters(params, jet.particles).thresholdReachesSurface);
    params.blend = 0.5;
    params.iterations = 4;
    EXPECT_EQ(resolveParameters(params, jet.particles).volumeOffset, VolumeOffset::Uniform);
    EXPECT_FALSE(resolveParameters(params, jet.particles).thresholdReachesSurface);
    params = SurfaceParameters();
    params.spacing = 1.0;
    params.threshold = 2.6;  // the user's r_0: the whole surface may lie inside
    EXPECT_EQ(resolveParameters(params, jet.particles).volumeOffset, VolumeOffset::Uniform);
    params.volumeOffset = VolumeOffset::Convex;
    EXPECT_EQ(resolveParameters(params, jet.particles).volumeOffset, VolumeOffset::Convex);
}

TEST(Fidelity, PreserveVolumeReachesTheTargetWithinItsLimit)
{
    const std::vector<openvdb::Vec3f> one{openvdb::Vec3f(0.0f)};
    const ParticleIndex index = ParticleIndex::build(one, 0.5);
    DensitySettings density;
    density.effectiveRadius = 1.0;
    density.voxelSize = 0.05;
    SurfaceMesh sphere = extractSurface(*rasterizeDensity(index, density), 1.0);  // radius 0.5
    computeNormals(sphere);
    const double volume = measureMesh(sphere).volume;

    SurfaceMesh grown = sphere;
    const double moved = preserveVolume(grown, 1.3 * volume);
    EXPECT_NEAR(measureMesh(grown).volume, 1.3 * volume, 0.002 * volume);
    EXPECT_NEAR(moved, 0.5 * (std::cbrt(1.3) - 1.0), 0.005);

    SurfaceMesh limited = sphere;
    EXPECT_DOUBLE_EQ(preserveVolume(limited, 1.3 * volume, 0.01), 0.01);
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { preserveVolume(limited, 0.0); }),
              "target volume must be > 0, got 0");
}
