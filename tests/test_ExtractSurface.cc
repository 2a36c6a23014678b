// SPDX-License-Identifier: Apache-2.0
#include "TestUtil.h"

#include <nonbloppy/ComputeNormals.h>
#include <nonbloppy/CorrectSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/ExtractSurface.h>
#include <nonbloppy/ParticleIndex.h>
#include <nonbloppy/RasterizeDensity.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>

using namespace nonbloppy;

namespace {

const openvdb::Vec3f kCentre(0.31f, -0.17f, 0.05f);

/// The density of one particle at kCentre.
openvdb::FloatGrid::Ptr singleParticleDensity(double radius, double voxelSize)
{
    const ParticleIndex index = ParticleIndex::build({kCentre}, radius / 2);
    DensitySettings settings;
    settings.effectiveRadius = radius;
    settings.voxelSize = voxelSize;
    return rasterizeDensity(index, settings);
}

SurfaceMesh singleParticleSurface(double radius, double threshold, double voxelSize)
{
    return extractSurface(*singleParticleDensity(radius, voxelSize), threshold);
}

} // namespace

TEST(ExtractSurface, OneParticleGivesASphereOfRadiusReOverOnePlusR0)
{
    for (const double threshold : {0.5, 1.0, 3.0}) {
        const double radius = 1.0, voxelSize = 0.04;
        const SurfaceMesh mesh = singleParticleSurface(radius, threshold, voxelSize);
        ASSERT_GT(mesh.points.size(), 100u);
        const double expected = radius / (1.0 + threshold);
        // Measured with voxels of 0.04: vertices at most 0.0009, 0.0011 and 0.0021 off for
        // r_0 = 0.5, 1 and 3, the mean radius 0.05%, 0.09% and 0.37% short.
        double radiusSum = 0.0;
        for (const openvdb::Vec3s& p : mesh.points) {
            const double distance = (p - kCentre).length();
            ASSERT_NEAR(distance, expected, voxelSize / 16) << "r_0 = " << threshold;
            radiusSum += distance;
        }
        EXPECT_NEAR(radiusSum / double(mesh.points.size()), expected, 0.005 * expected) << "r_0 = " << threshold;
    }
}

TEST(ExtractSurface, PolygonsFaceOutOfTheFluid)
{
    const SurfaceMesh mesh = singleParticleSurface(1.0, 1.0, 0.05);
    ASSERT_FALSE(mesh.quads.empty());
    // Right-hand-rule normal of every polygon points away from the particle.
    for (const openvdb::Vec4I& q : mesh.quads) {
        const openvdb::Vec3d a(mesh.points[q[0]]), b(mesh.points[q[1]]), c(mesh.points[q[2]]), d(mesh.points[q[3]]);
        const openvdb::Vec3d normal = (c - a).cross(d - b);
        const openvdb::Vec3d outward = (a + b + c + d) / 4.0 - openvdb::Vec3d(kCentre);
        ASSERT_GT(normal.dot(outward), 0.0);
    }
    for (const openvdb::Vec3I& t : mesh.triangles) {
        const openvdb::Vec3d a(mesh.points[t[0]]), b(mesh.points[t[1]]), c(mesh.points[t[2]]);
        ASSERT_GT((b - a).cross(c - a).dot((a + b + c) / 3.0 - openvdb::Vec3d(kCentre)), 0.0);
    }
}

TEST(ExtractSurface, AdaptivityMergesPolygonsAndIsChecked)
{
    const openvdb::FloatGrid::Ptr grid = singleParticleDensity(1.0, 0.04);
    const SurfaceMesh full = extractSurface(*grid, 1.0, 0.0);
    const SurfaceMesh adaptive = extractSurface(*grid, 1.0, 0.5);
    EXPECT_LT(adaptive.polygonCount(), full.polygonCount());
    try {
        extractSurface(*grid, 1.0, 1.5);
        FAIL() << "adaptivity 1.5 accepted";
    } catch (const ParameterError& e) {
        EXPECT_STREQ(e.what(), "--adaptivity must lie in [0,1], got 1.5");
    }
}

TEST(ExtractSurface, RefusesALevelSetWhichWouldComeOutInsideOut)
{
    // A signed distance field is smaller inside: meshed as a density it would face inwards.
    const openvdb::FloatGrid::Ptr sphere = openvdb::FloatGrid::create(3.0f);
    sphere->setName("sphere");
    sphere->setGridClass(openvdb::GRID_LEVEL_SET);
    sphere->tree().setValue(openvdb::Coord(0), -1.0f);
    const std::string expected = "needs a density grid (larger values inside), got the level set 'sphere' "
                                 "(smaller values inside): mesh it with openvdb::tools::volumeToMesh";
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { extractSurface(*sphere, 0.0); }),
              "extractSurface " + expected);
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { tileDeepInterior(*sphere, 0.0); }),
              "tileDeepInterior " + expected);
    const openvdb::DoubleGrid::Ptr wide = openvdb::DoubleGrid::create(3.0);
    wide->setName("sphere");
    wide->setGridClass(openvdb::GRID_LEVEL_SET);
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { extractSurface(*wide, 0.0); }),
              "extractSurface " + expected);
    // The same values classed as anything else are refused for their background: outside the
    // active voxels the grid holds 3, above the threshold, which is inside.
    sphere->setGridClass(openvdb::GRID_UNKNOWN);
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { extractSurface(*sphere, 0.0); }),
              "--threshold must lie above the density grid's background value 3 (its value outside the fluid), got 0");
}

TEST(ExtractSurface, AThresholdAtOrBelowTheBackgroundIsRefused)
{
    // r_0 <= 0 returned an empty mesh without a word (bug hunt), and tileDeepInterior() and
    // offsetSurface() took NaN (the latter made every vertex NaN).
    const openvdb::FloatGrid::Ptr grid = singleParticleDensity(1.0, 0.1);
    for (const double threshold : {0.0, -1.0}) {
        std::ostringstream expected;
        expected << "--threshold must lie above the density grid's background value 0 (its value outside the "
                    "fluid), got " << threshold;
        EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { extractSurface(*grid, threshold); }), expected.str());
        EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { tileDeepInterior(*grid, threshold); }), expected.str());
    }
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { tileDeepInterior(*grid, std::nan("")); }),
              "--threshold must be finite, got nan");
    SurfaceMesh mesh = extractSurface(*grid, 1.0);
    EXPECT_GT(mesh.points.size(), 10u);
    computeNormals(mesh);
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { offsetSurface(mesh, std::nan("")); }),
              "offset distance must be finite, got nan");
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] {
                  offsetSurface(mesh, std::numeric_limits<double>::infinity());
              }), "offset distance must be finite, got inf");
}
