// SPDX-License-Identifier: Apache-2.0
#include "TestUtil.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/Kernel.h>
#include <nonbloppy/ParticleIndex.h>
#include <nonbloppy/RasterizeDensity.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <limits>
#include <random>

using namespace nonbloppy;

namespace {

std::vector<openvdb::Vec3f> randomParticles(size_t count, unsigned seed)
{
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> coordinate(-0.4f, 0.6f);
    std::vector<openvdb::Vec3f> positions(count);
    for (auto& p : positions) p = openvdb::Vec3f(coordinate(random), coordinate(random), coordinate(random));
    return positions;
}

double bruteForceDensity(const std::vector<openvdb::Vec3f>& positions, const openvdb::Vec3d& x, double radius)
{
    double sum = 0.0;
    for (const auto& p : positions) sum += mpsWeight(float((openvdb::Vec3d(p) - x).length()), float(radius));
    return sum;
}

openvdb::FloatGrid::Ptr rasterize(const std::vector<openvdb::Vec3f>& positions, double radius, double voxelSize)
{
    const ParticleIndex index = ParticleIndex::build(positions, radius / 2);
    DensitySettings settings;
    settings.effectiveRadius = radius;
    settings.voxelSize = voxelSize;
    return rasterizeDensity(index, settings);
}

/// Every voxel of @a box (which holds all particles' supports) is active exactly where some
/// particle is closer than r_e, with the brute-force value; nothing is active outside it.
void expectBruteForceValues(const openvdb::FloatGrid& grid, const std::vector<openvdb::Vec3f>& positions,
                            double radius, const openvdb::CoordBBox& box)
{
    auto accessor = grid.getConstAccessor();
    size_t activeSeen = 0;
    for (auto ijk = box.begin(); ijk; ++ijk) {
        const double expected = bruteForceDensity(positions, grid.indexToWorld(*ijk), radius);
        float value = 0.0f;
        const bool active = accessor.probeValue(*ijk, value);
        ASSERT_EQ(active, expected > 0.0) << *ijk;
        if (active) {
            ++activeSeen;
            ASSERT_NEAR(value, expected, 1e-4 * (1.0 + expected)) << *ijk;
        }
    }
    EXPECT_EQ(activeSeen, grid.activeVoxelCount());
}

} // namespace

TEST(RasterizeDensity, MatchesBruteForceSumAndActivatesExactlyTheSupport)
{
    const double radius = 0.15, voxelSize = 0.04;
    const std::vector<openvdb::Vec3f> positions = randomParticles(300, 1);
    const openvdb::FloatGrid::Ptr grid = rasterize(positions, radius, voxelSize);
    EXPECT_EQ(grid->getName(), "density");
    EXPECT_EQ(grid->getGridClass(), openvdb::GRID_FOG_VOLUME);
    EXPECT_EQ(grid->background(), 0.0f);

    expectBruteForceValues(*grid, positions, radius, openvdb::CoordBBox(openvdb::Coord(-15), openvdb::Coord(20)));
}

TEST(RasterizeDensity, WideSupportsAndGappedColumnsMatchTheBruteForceSum)
{
    // r_e = 10.5 h: each support is 21 voxels tall, three 8-voxel vectors. Two clusters 1.2
    // apart in z put leaves with a gap between them into one column of the task (8 leaves,
    // 64 voxels, from the lowest), and the clusters' supports overlap neither the gap nor
    // each other.
    const double radius = 0.21, voxelSize = 0.02;
    std::mt19937 random(3);
    std::uniform_real_distribution<float> offset(-0.05f, 0.05f);
    std::vector<openvdb::Vec3f> positions;
    for (const float z : {0.0f, 1.2f}) {
        for (int n = 0; n < 40; ++n) positions.emplace_back(offset(random), offset(random), z + offset(random));
    }
    const openvdb::FloatGrid::Ptr grid = rasterize(positions, radius, voxelSize);
    expectBruteForceValues(*grid, positions, radius,
                           openvdb::CoordBBox(openvdb::Coord(-14, -14, -14), openvdb::Coord(14, 14, 75)));
    EXPECT_FALSE(grid->tree().isValueOn(openvdb::Coord(0, 0, 30)));  // the gap stays empty
}

TEST(RasterizeDensity, ClustersScatteredOverColumnsOfManyStacksMatchTheBruteForceSum)
{
    // A task fills a column 4 x 4 leaf stacks wide (32 voxels along x and y). Small clusters
    // with empty stacks between them, on both sides of column boundaries (x and y = 0 and
    // 32 voxels, h = 0.02) and at different heights, each sum only their own particles.
    const double radius = 0.05, voxelSize = 0.02;
    std::mt19937 random(7);
    std::uniform_real_distribution<float> offset(-0.02f, 0.02f);
    std::vector<openvdb::Vec3f> positions;
    const openvdb::Vec3f centres[] = {{0.05f, 0.05f, 0.0f},  {0.45f, 0.05f, 0.3f},  {0.05f, 0.45f, -0.2f},
                                      {0.63f, 0.63f, 0.0f},  {0.66f, 0.1f, 0.0f},   {-0.01f, 0.3f, 0.1f},
                                      {0.3f, -0.02f, 0.2f}};
    for (const openvdb::Vec3f& centre : centres) {
        for (int n = 0; n < 12; ++n) positions.push_back(centre + openvdb::Vec3f(offset(random), offset(random), offset(random)));
    }
    const openvdb::FloatGrid::Ptr grid = rasterize(positions, radius, voxelSize);
    expectBruteForceValues(*grid, positions, radius,
                           openvdb::CoordBBox(openvdb::Coord(-6, -6, -16), openvdb::Coord(40, 40, 20)));
    EXPECT_FALSE(grid->tree().isValueOn(openvdb::Coord(16, 16, 0)));  // between the clusters
}

TEST(RasterizeDensity, VoxelsFarWiderThanTheSupportMatchTheBruteForceSum)
{
    // h = 64 r_e: a leaf column spans 512 h, some 650,000 index cells per axis around 300
    // particles. The cell walk is clipped to the index's leaves; unclipped it took minutes.
    // Only voxel centres within r_e of a particle are active.
    const double radius = 0.1, voxelSize = 6.4;
    std::vector<openvdb::Vec3f> positions = randomParticles(300, 5);
    positions.push_back(openvdb::Vec3f(6.4f, 0.0f, -6.4f));  // on a voxel centre
    const openvdb::FloatGrid::Ptr grid = rasterize(positions, radius, voxelSize);
    EXPECT_TRUE(grid->tree().isValueOn(openvdb::Coord(1, 0, -1)));
    expectBruteForceValues(*grid, positions, radius, openvdb::CoordBBox(openvdb::Coord(-2), openvdb::Coord(2)));
}

TEST(RasterizeDensity, VoxelOnTopOfAParticleStaysFinite)
{
    const std::vector<openvdb::Vec3f> one{openvdb::Vec3f(0.2f, 0.0f, -0.4f)};
    const openvdb::FloatGrid::Ptr grid = rasterize(one, 1.0, 0.1);
    const float value = grid->tree().getValue(openvdb::Coord(2, 0, -4));
    EXPECT_TRUE(std::isfinite(value));
    EXPECT_NEAR(value, 1.0 / kMinDistanceFraction - 1.0, 1e-2);
}

TEST(RasterizeDensity, BitIdenticalForOneAndTwoThreads)
{
    const std::vector<openvdb::Vec3f> positions = randomParticles(5000, 2);
    openvdb::FloatGrid::Ptr serial, parallel;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        serial = rasterize(positions, 0.08, 0.02);
    }
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
        parallel = rasterize(positions, 0.08, 0.02);
    }
    ASSERT_EQ(serial->activeVoxelCount(), parallel->activeVoxelCount());
    auto accessor = parallel->getConstAccessor();
    for (auto it = serial->cbeginValueOn(); it; ++it) {
        float other = 0.0f;
        ASSERT_TRUE(accessor.probeValue(it.getCoord(), other));
        ASSERT_EQ(*it, other) << it.getCoord();  // bitwise, not approximately
    }
}

TEST(RasterizeDensity, RejectsBadSettings)
{
    const ParticleIndex index = ParticleIndex::build({openvdb::Vec3f(0.0f)}, 0.5);
    DensitySettings settings;
    settings.effectiveRadius = 0.0;
    settings.voxelSize = 0.1;
    try {
        rasterizeDensity(index, settings);
        FAIL() << "r_e = 0 accepted";
    } catch (const ParameterError& e) {
        EXPECT_STREQ(e.what(), "--radius must be > 0, got 0");
    }
    settings.effectiveRadius = 1.0;
    settings.voxelSize = -0.5;
    try {
        rasterizeDensity(index, settings);
        FAIL() << "h < 0 accepted";
    } catch (const ParameterError& e) {
        EXPECT_STREQ(e.what(), "--voxel-size must be > 0, got -0.5");
    }
    // Not finite: checkParameters()'s words, not "must be > 0, got inf".
    settings.voxelSize = std::numeric_limits<double>::infinity();
    try {
        rasterizeDensity(index, settings);
        FAIL() << "h = inf accepted";
    } catch (const ParameterError& e) {
        EXPECT_STREQ(e.what(), "--voxel-size must be finite, got inf");
    }
    settings.voxelSize = 0.1;
    settings.effectiveRadius = std::numeric_limits<double>::quiet_NaN();
    try {
        rasterizeDensity(index, settings);
        FAIL() << "r_e = nan accepted";
    } catch (const ParameterError& e) {
        EXPECT_STREQ(e.what(), "--radius must be finite, got nan");
    }
    settings.effectiveRadius = 1.0;
    // r_e/h = 1000 would make a 4·10⁹-voxel sphere (18 GB) of this one particle; 32 is the limit,
    // for a caller's transform as well.
    settings.voxelSize = 0.001;
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { rasterizeDensity(index, settings); }),
              "--voxel-size 0.001 is too small for --radius 1: at most 32 voxels per radius");
    settings.transform = openvdb::math::Transform::createLinearTransform(0.03);
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { rasterizeDensity(index, settings); }),
              "--voxel-size 0.03 is too small for --radius 1: at most 32 voxels per radius");
    settings.transform = openvdb::math::Transform::createLinearTransform(1.0 / 32.0);
    EXPECT_GT(rasterizeDensity(index, settings)->activeVoxelCount(), 130000u);  // (4π/3)·32³ ≈ 137k
    // A caller's transform below OpenVDB's smallest scale went through (API review).
    const ParticleIndex tiny = ParticleIndex::build({openvdb::Vec3f(0.0f)}, 1.5e-5);
    settings.effectiveRadius = 4.35e-5;
    settings.transform = openvdb::math::Transform::createLinearTransform(1.45e-5);
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { rasterizeDensity(tiny, settings); }),
              "--voxel-size 1.45e-05 is below 1.5e-05, the smallest OpenVDB accepts: give the positions in a "
              "smaller unit");
    // Past r_e = 1e18 the kernel's squared lengths overflow single precision: r_e = 4e19
    // gave a particle's voxels within reach density 0 (API review).
    const ParticleIndex huge = ParticleIndex::build({openvdb::Vec3f(0.0f)}, 2.0e19);
    settings.effectiveRadius = 4.0e19;
    settings.transform = openvdb::math::Transform::createLinearTransform(1.0e19);
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { rasterizeDensity(huge, settings); }),
              "--radius 4e+19 is too large: at most 1e+18 (lengths are squared in single precision); give the "
              "positions in a larger unit");
    settings.effectiveRadius = 1.0;
    settings.transform.reset();
    // OpenVDB's transforms refuse such a scale with "Non-zero scale values required".
    settings.voxelSize = 1e-6;
    try {
        rasterizeDensity(index, settings);
        FAIL() << "h below OpenVDB's smallest accepted";
    } catch (const ParameterError& e) {
        EXPECT_STREQ(e.what(),
                     "--voxel-size 1e-06 is below 1.5e-05, the smallest OpenVDB accepts: give the positions in a "
                     "smaller unit");
    }
    try {
        ParticleIndex::build({openvdb::Vec3f(0.0f)}, 1e-6);
        FAIL() << "cell below OpenVDB's smallest accepted";
    } catch (const ParameterError& e) {
        EXPECT_STREQ(e.what(),
                     "particle index cell size 1e-06 is below 1.5e-05, the smallest OpenVDB accepts: give the "
                     "positions in a smaller unit");
    }
}

TEST(ParticleIndex, KeepsEveryParticleOnceAndMapsBackToTheOriginal)
{
    const std::vector<openvdb::Vec3f> positions = randomParticles(2000, 3);
    const ParticleIndex index = ParticleIndex::build(positions, 0.05);
    ASSERT_EQ(index.size(), positions.size());
    std::vector<bool> seen(positions.size(), false);
    for (size_t k = 0; k < index.size(); ++k) {
        const uint32_t original = index.originalIndex()[k];
        ASSERT_LT(original, positions.size());
        EXPECT_FALSE(seen[original]);
        seen[original] = true;
        EXPECT_EQ(index.sortedPositions()[k], positions[original]);
    }
    EXPECT_EQ(index.cellSize(), 0.05);
    EXPECT_TRUE(index.indexGrid());
}

TEST(ParticleIndex, RejectsNonFinitePositions)
{
    std::vector<openvdb::Vec3f> positions(10, openvdb::Vec3f(0.0f));
    positions[7][1] = std::nanf("");
    try {
        ParticleIndex::build(positions, 0.1);
        FAIL() << "NaN accepted";
    } catch (const ParameterError& e) {
        EXPECT_STREQ(e.what(), "non-finite position of particle 7");
    }
    // The first of several, wherever the parallel scan's pieces start.
    std::vector<openvdb::Vec3f> many(200000, openvdb::Vec3f(0.0f));
    for (size_t n : {size_t(199999), size_t(150000), size_t(64123), size_t(100001)}) {
        many[n][2] = std::numeric_limits<float>::infinity();
    }
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { ParticleIndex::build(many, 0.1); }),
              "non-finite position of particle 64123");
}

TEST(ParticleIndex, RejectsCoordinatesBeyondThe32BitIndexSpace)
{
    // 2.5e8 / 0.1 is 2.5e9 cells from the origin, past what an int32 coordinate holds.
    std::vector<openvdb::Vec3f> positions(100000, openvdb::Vec3f(1.0f));
    positions[54321] = openvdb::Vec3f(0.0f, -2.5e8f, 0.0f);
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { ParticleIndex::build(positions, 0.1); }),
              "particle coordinates up to 2.5e+08 are too far from the origin for a cell size of 0.1 "
              "(32-bit index space)");
    // The same particle with cells of 1 is 2.5e8 cells away: accepted.
    EXPECT_EQ(ParticleIndex::build(positions, 1.0).size(), positions.size());
}
