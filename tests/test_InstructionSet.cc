// SPDX-License-Identifier: Apache-2.0
/// @file test_InstructionSet.cc
/// @brief The AVX2 and AVX-512F copies of the hot loops (src/InstructionSet.h) give the
///        baseline copies' bits, so meshes are the same on every machine. On a CPU without
///        AVX2 every run takes the baseline copy and the tests are skipped; without AVX-512F,
///        Auto takes the AVX2 copy and the AVX-512F exponential's test is skipped.

#include "TestUtil.h"

#include "../src/ExpNonPositive.h"
#include "../src/InstructionSet.h"

#include <nonbloppy/ExtractSurface.h>
#include <nonbloppy/ReadParticles.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

using namespace nonbloppy;
using namespace nonbloppy::instruction_set_internal;

namespace {

/// The real dam-break frame (24,389 particles), its index and the benchmark's r_e and h.
class SameBitsTest : public ::testing::Test
{
protected:
    void SetUp() override
    {
        if (!useAvx2(InstructionSet::Auto)) GTEST_SKIP() << "no AVX2 here: only the baseline copy runs";
        density.effectiveRadius = 0.1;
        density.voxelSize = 0.025;
    }

    const ParticleSet frame =
        readParticles(std::string(NONBLOPPY_TEST_DATA_DIR) + "/dam_break_frame_23_24389_particles.vtk");
    const ParticleIndex index = ParticleIndex::build(frame.positions, 0.05);
    DensitySettings density;
};

/// The two grids have the same leaves, with the same active voxels and value bits.
void expectSameLeaves(const openvdb::FloatGrid& automatic, const openvdb::FloatGrid& baseline)
{
    ASSERT_EQ(automatic.tree().leafCount(), baseline.tree().leafCount());
    size_t differing = 0;
    auto other = baseline.tree().cbeginLeaf();
    for (auto leaf = automatic.tree().cbeginLeaf(); leaf; ++leaf, ++other) {
        ASSERT_TRUE(other);
        ASSERT_EQ(leaf->origin(), other->origin());
        differing += leaf->getValueMask() != other->getValueMask()
                     || std::memcmp(leaf->buffer().data(), other->buffer().data(),
                                    sizeof(float) * leaf->SIZE) != 0;
    }
    EXPECT_EQ(differing, 0u);
}

} // namespace

TEST_F(SameBitsTest, RasterizeDensityLeafByLeaf)
{
    const openvdb::FloatGrid::Ptr automatic = rasterizeDensity(index, density, nullptr, InstructionSet::Auto);
    const openvdb::FloatGrid::Ptr baseline = rasterizeDensity(index, density, nullptr, InstructionSet::Baseline);
    ASSERT_GT(automatic->activeVoxelCount(), 250000u);
    expectSameLeaves(*automatic, *baseline);
}

TEST_F(SameBitsTest, RasterizeDensityWithSupportsManyVectorsTall)
{
    // r_e = 5.2 h: 11-voxel supports, two 8-lane vectors a row, the second mostly masked.
    density.voxelSize = 0.1 / 5.2;
    const openvdb::FloatGrid::Ptr automatic = rasterizeDensity(index, density, nullptr, InstructionSet::Auto);
    const openvdb::FloatGrid::Ptr baseline = rasterizeDensity(index, density, nullptr, InstructionSet::Baseline);
    expectSameLeaves(*automatic, *baseline);
}

TEST_F(SameBitsTest, RelaxVerticesWithCappedSteps)
{
    // A large blend and a cap on the step: both branches of the step are taken.
    const SurfaceMesh extracted = extractSurface(*rasterizeDensity(index, density), 6.666);
    ASSERT_GT(extracted.points.size(), 30000u);
    RelaxSettings settings;
    settings.effectiveRadius = 0.1;
    settings.blend = 0.7;
    settings.iterations = 3;
    settings.maxStep = 0.01;
    SurfaceMesh automatic = extracted, baseline = extracted;
    relaxVertices(automatic, index, settings, nullptr, InstructionSet::Auto);
    relaxVertices(baseline, index, settings, nullptr, InstructionSet::Baseline);
    ASSERT_EQ(automatic.points.size(), baseline.points.size());
    EXPECT_EQ(std::memcmp(automatic.points.data(), baseline.points.data(),
                          automatic.points.size() * sizeof(openvdb::Vec3s)), 0);
    size_t moved = 0;
    for (size_t i = 0; i < extracted.points.size(); ++i) moved += automatic.points[i] != extracted.points[i];
    EXPECT_GT(moved, extracted.points.size() / 2);
}

TEST_F(SameBitsTest, SmoothSurfaceOfTheRelaxedFrame)
{
    // The frame's relaxed surface, as buildSurface() smooths it (spacing 0.05: its filter is
    // 0.035 wide), triangles and quads both: the normal rounds take the AVX2 copy's lanes.
    SurfaceMesh extracted = extractSurface(*rasterizeDensity(index, density), 3.6);
    ASSERT_GT(extracted.quads.size(), 30000u);
    for (size_t q = 0; q < 200; ++q) {  // some triangles too, as a quad's halves
        const openvdb::Vec4I quad = extracted.quads.back();
        extracted.quads.pop_back();
        extracted.triangles.emplace_back(quad[0], quad[1], quad[2]);
        extracted.triangles.emplace_back(quad[0], quad[2], quad[3]);
    }
    RelaxSettings relax;
    relax.effectiveRadius = 0.1;
    relaxVertices(extracted, index, relax);
    SmoothSettings settings;
    settings.spatialWidth = kDefaultSmoothWidthOverSpacing * 0.05;
    // Auto takes the AVX-512F copy where the CPU has AVX-512F; Avx2 the AVX2 copy.
    SurfaceMesh automatic = extracted, avx2 = extracted, baseline = extracted;
    smoothSurface(automatic, settings, nullptr, InstructionSet::Auto);
    smoothSurface(avx2, settings, nullptr, InstructionSet::Avx2);
    smoothSurface(baseline, settings, nullptr, InstructionSet::Baseline);
    EXPECT_EQ(std::memcmp(automatic.points.data(), baseline.points.data(),
                          automatic.points.size() * sizeof(openvdb::Vec3s)), 0);
    EXPECT_EQ(std::memcmp(avx2.points.data(), baseline.points.data(), avx2.points.size() * sizeof(openvdb::Vec3s)),
              0);
    size_t moved = 0;
    for (size_t i = 0; i < extracted.points.size(); ++i) moved += automatic.points[i] != extracted.points[i];
    EXPECT_GT(moved, extracted.points.size() / 2);
}

TEST(SameBitsSmallMeshes, SmoothSurfaceOfMeshesSmallerThanTheLanes)
{
    // The vector copies take 8 or 16 polygons, and 8 vertices, a step: meshes of fewer,
    // groups cut short at the end, a vertex on 17 polygons beside ones on two, and a vertex
    // on none (it stays where it is) must give the baseline's bits too. The arrays' last
    // normal and plane are read 16 and 32 bytes at a time (past them: padding).
    if (!useAvx2(InstructionSet::Auto)) GTEST_SKIP() << "no AVX2 here: only the baseline copy runs";
    std::vector<SurfaceMesh> meshes(3);
    meshes[0].points = {{0, 0, 0}, {1, 0, 0.1f}, {0, 1, 0.2f}};
    meshes[0].triangles = {{0, 1, 2}};
    meshes[1].points = {{0, 0, 0}, {1, 0, 0.1f}, {1, 1, 0}, {0, 1, 0.2f}, {5, 5, 5}};  // 4: on no polygon
    meshes[1].quads = {{0, 1, 2, 3}};
    // A fan of 17 triangles around vertex 0 on a bumpy disc, and a quad strip beside it.
    SurfaceMesh& fan = meshes[2];
    fan.points.push_back({0, 0, 0.3f});
    for (int k = 0; k < 17; ++k) {
        const float angle = 6.2831853f * float(k) / 17.0f;
        fan.points.push_back({std::cos(angle), std::sin(angle), 0.05f * float(k % 3)});
    }
    for (uint32_t k = 0; k < 17; ++k) fan.triangles.push_back({0, 1 + k, 1 + (k + 1) % 17});
    for (uint32_t k = 0; k < 5; ++k) {
        const uint32_t first = uint32_t(fan.points.size());
        fan.points.push_back({3.0f + float(k), 0, 0.1f * float(k % 2)});
        fan.points.push_back({3.0f + float(k), 1, 0});
        if (k > 0) fan.quads.push_back({first - 2, first, first + 1, first - 1});
    }
    fan.points.push_back({9, 9, 9});  // on no polygon
    SmoothSettings settings;
    settings.spatialWidth = 0.7;
    for (size_t m = 0; m < meshes.size(); ++m) {
        SCOPED_TRACE(m);
        SurfaceMesh automatic = meshes[m], avx2 = meshes[m], baseline = meshes[m];
        smoothSurface(automatic, settings, nullptr, InstructionSet::Auto);
        smoothSurface(avx2, settings, nullptr, InstructionSet::Avx2);
        smoothSurface(baseline, settings, nullptr, InstructionSet::Baseline);
        const size_t bytes = baseline.points.size() * sizeof(openvdb::Vec3s);
        EXPECT_EQ(std::memcmp(automatic.points.data(), baseline.points.data(), bytes), 0);
        EXPECT_EQ(std::memcmp(avx2.points.data(), baseline.points.data(), bytes), 0);
        if (m > 0) EXPECT_EQ(automatic.points.back(), meshes[m].points.back());  // on no polygon
    }
    // The fan moved: its bumps are flattened towards their faces' filtered planes.
    SurfaceMesh smoothed = meshes[2];
    smoothSurface(smoothed, settings, nullptr, InstructionSet::Baseline);
    size_t moved = 0;
    for (size_t i = 0; i < 18; ++i) moved += smoothed.points[i] != meshes[2].points[i];
    EXPECT_GT(moved, 9u);
}

#if NONBLOPPY_HAS_AVX2_COPY
namespace {

/// 2^23 arguments across [kExpLowest, 0] and the special ones, padded with zeros to a
/// multiple of 16.
std::vector<float> exponentialArguments()
{
    std::vector<float> x;
    for (int i = 0; i <= (1 << 23); ++i) x.push_back(exp_internal::kExpLowest * float(i) / float(1 << 23));
    for (float special : {0.0f, -0.0f, -87.34f, -88.0f, -1000.0f, -std::numeric_limits<float>::infinity(),
                          std::numeric_limits<float>::quiet_NaN(), -std::numeric_limits<float>::denorm_min()}) {
        x.push_back(special);
    }
    while (x.size() % 16) x.push_back(0.0f);
    return x;
}

/// expNonPositiveAvx2() on every value of @a x, eight at a time.
NONBLOPPY_TARGET_AVX2 std::vector<float> eightLaneExponentials(const std::vector<float>& x)
{
    std::vector<float> y(x.size());
    for (size_t i = 0; i < x.size(); i += 8) {
        _mm256_storeu_ps(&y[i], exp_internal::expNonPositiveAvx2(_mm256_loadu_ps(&x[i])));
    }
    return y;
}

/// expNonPositiveAvx512() on every value of @a x, sixteen at a time.
NONBLOPPY_TARGET_AVX512 std::vector<float> sixteenLaneExponentials(const std::vector<float>& x)
{
    std::vector<float> y(x.size());
    for (size_t i = 0; i < x.size(); i += 16) {
        _mm512_storeu_ps(&y[i], exp_internal::expNonPositiveAvx512(_mm512_loadu_ps(&x[i])));
    }
    return y;
}

/// How many of @a y, a vector copy's e^x for each of @a x, differ in any bit from the
/// scalar copy's.
size_t differingFromScalar(const std::vector<float>& x, const std::vector<float>& y)
{
    size_t differing = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        const float scalar = exp_internal::expNonPositive(x[i]);
        differing += std::memcmp(&scalar, &y[i], sizeof(float)) != 0;
    }
    return differing;
}

} // namespace

TEST_F(SameBitsTest, ExponentialOverItsWholeRange)
{
    // Every lane gives the scalar copy's bits.
    const std::vector<float> x = exponentialArguments();
    EXPECT_EQ(differingFromScalar(x, eightLaneExponentials(x)), 0u);
}

TEST_F(SameBitsTest, SixteenLaneExponentialOverItsWholeRange)
{
    if (!useAvx512(InstructionSet::Auto)) GTEST_SKIP() << "no AVX-512F here";
    const std::vector<float> x = exponentialArguments();
    EXPECT_EQ(differingFromScalar(x, sixteenLaneExponentials(x)), 0u);
}
#endif
