// SPDX-License-Identifier: Apache-2.0
/// @file test_InstructionSet.cc
/// @brief The AVX2 copies of the hot loops (src/InstructionSet.h) give the baseline copies'
///        bits, so meshes are the same on every machine. On a CPU without AVX2 both runs
///        take the baseline copy and the tests are skipped.

#include "TestUtil.h"

#include "../src/InstructionSet.h"

#include <nonbloppy/ExtractSurface.h>
#include <nonbloppy/ReadParticles.h>

#include <gtest/gtest.h>

#include <cstring>
#include <string>

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
