// SPDX-License-Identifier: Apache-2.0
// Tests for meshToLevelSet(): the signed distance to a closed mesh, and its checks.
#include "TestUtil.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/MeshToLevelSet.h>

#include <gtest/gtest.h>

#include <limits>
#include <string>

#include <atomic>

using nonbloppy::ParameterError;
using nonbloppy::SurfaceMesh;

namespace {

/// The unit cube [0,1]³ as 6 outward quads.
SurfaceMesh unitCube()
{
    SurfaceMesh cube;
    for (int i = 0; i < 8; ++i) cube.points.emplace_back(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
    cube.quads = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    return cube;
}

} // namespace

TEST(MeshToLevelSet, SignedDistanceToACube)
{
    const openvdb::FloatGrid::Ptr grid = nonbloppy::meshToLevelSet(unitCube(), 0.1);
    EXPECT_EQ(grid->getName(), "surface");
    EXPECT_EQ(grid->getGridClass(), openvdb::GRID_LEVEL_SET);
    const auto value = [&](double x, double y, double z) {
        return grid->tree().getValue(grid->transform().worldToIndexCellCentered(openvdb::Vec3d(x, y, z)));
    };
    EXPECT_NEAR(value(0.5, 0.5, 1.1), 0.1, 1e-5);   // outside, one voxel above the top
    EXPECT_NEAR(value(0.5, 0.5, 0.9), -0.1, 1e-5);  // inside, one voxel below it
    EXPECT_NEAR(value(0.5, 0.5, 1.0), 0.0, 1e-5);
}

TEST(MeshToLevelSet, BadInputIsAParameterError)
{
    // A vertex index out of range crashed inside OpenVDB; a voxel below kMinCellSize threw
    // OpenVDB's ArithmeticError, which no caller catching nonbloppy::Error sees.
    SurfaceMesh cube = unitCube();
    cube.triangles.push_back({0, 1, 1u << 30});
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { nonbloppy::meshToLevelSet(cube, 0.1); }),
              "polygon 0 references vertex 1073741824 but the mesh has 8 vertices");
    cube.triangles.clear();
    cube.quads[5][2] = 8;
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { nonbloppy::meshToLevelSet(cube, 0.1); }),
              "polygon 5 references vertex 8 but the mesh has 8 vertices");
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { nonbloppy::meshToLevelSet(unitCube(), 1e-9); }),
              "--voxel-size 1e-09 is below 1.5e-05, the smallest OpenVDB accepts: give the positions in a "
              "smaller unit");
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { nonbloppy::meshToLevelSet(unitCube(), 0.0); }),
              "--voxel-size must be > 0, got 0");
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>(
                  [&] { nonbloppy::meshToLevelSet(unitCube(), std::numeric_limits<double>::infinity()); }),
              "--voxel-size must be finite, got inf");
}

TEST(MeshToLevelSet, VerticesAndBandsItCannotHoldAreRefusedBeforeAnyGridIsMade)
{
    // Each of these ended the process (std::bad_alloc escaping OpenVDB's tasks), hung where
    // no interrupter was asked, or gave an empty grid.
    SurfaceMesh cube = unitCube();
    cube.points[3][1] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { nonbloppy::meshToLevelSet(cube, 0.1); }),
              "non-finite position of vertex 3");
    cube.points[3][1] = std::numeric_limits<float>::infinity();
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { nonbloppy::meshToLevelSet(cube, 0.1); }),
              "non-finite position of vertex 3");

    // Moved 5e7 from the origin: 2.5e9 voxels out at h = 0.02, beyond 32-bit coordinates.
    SurfaceMesh far = unitCube();
    for (openvdb::Vec3s& p : far.points) p[0] += 5.0e7f;
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { nonbloppy::meshToLevelSet(far, 0.02); }),
              "mesh coordinates up to 5e+07 are too far from the origin for a voxel size of 0.02 (32-bit "
              "index space)");
    // 1e7 out (5e8 voxels) still works, and gives the cube's band as at the origin.
    SurfaceMesh near = unitCube();
    for (openvdb::Vec3s& p : near.points) p[0] += 1.0e7f;
    EXPECT_GT(nonbloppy::meshToLevelSet(near, 0.02)->activeVoxelCount(), 0u);

    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>(
                  [&] { nonbloppy::meshToLevelSet(unitCube(), 0.1, std::numeric_limits<float>::infinity()); }),
              "level set half width must be >= 1 voxel and finite, got inf");
    EXPECT_EQ(nonbloppy_test::messageOf<ParameterError>([&] { nonbloppy::meshToLevelSet(unitCube(), 0.1, 0.5f); }),
              "level set half width must be >= 1 voxel and finite, got 0.5");

    // One triangle of 5e5 m² at h = 0.01: 3e10 band voxels, about 1e3 GB, more than any
    // machine this runs on (the probe's 8 GB limit was hit after 38 s).
    SurfaceMesh sail;
    sail.points = {{0, 0, 0}, {1000, 0, 0}, {0, 1000, 0}};
    sail.triangles = {{0, 1, 2}};
    const std::string message =
        nonbloppy_test::messageOf<ParameterError>([&] { nonbloppy::meshToLevelSet(sail, 0.01); });
    EXPECT_EQ(message.rfind("the level set's narrow band would hold about 3e+10 voxels, about 960 GB at its "
                            "peak, more than the ", 0), 0u) << message;
    const std::string advice = " this process can still take: use a voxel size larger than 0.01 or a half width "
                               "below 3";
    ASSERT_GT(message.size(), advice.size());
    EXPECT_EQ(message.substr(message.size() - advice.size()), advice) << message;

    // A small mesh's band grows as the half width cubed, not as its area times the width:
    // one triangle of 0.005 at h = 1 made 902,813 voxels at half width 60, which the area
    // put at 0.6, and half width 2000 passed the check (API review). Its ball is 3.4e10
    // voxels, about 1.07 TB.
    SurfaceMesh chip;
    chip.points = {{0, 0, 0}, {0.1f, 0, 0}, {0, 0.1f, 0}};
    chip.triangles = {{0, 1, 2}};
    const std::string chipMessage =
        nonbloppy_test::messageOf<ParameterError>([&] { nonbloppy::meshToLevelSet(chip, 1.0, 2000.0f); });
    EXPECT_EQ(chipMessage.rfind("the level set's narrow band would hold about 3.4e+10 voxels, about 1.07 TB at its "
                                "peak, more than the ", 0), 0u) << chipMessage;
}

TEST(MeshToLevelSet, AnInterrupterStopsItAndOneThatDoesNotChangesNothing)
{
    // --vdb-surface spent seconds in meshToVolume on large frames with SIGTERM unheard.
    struct StopAfter : openvdb::util::NullInterrupter
    {
        explicit StopAfter(int calls) : remaining(calls) {}
        bool wasInterrupted(int = -1) override { return --remaining < 0; }
        std::atomic<int> remaining;
    };
    const SurfaceMesh cube = unitCube();
    for (const int calls : {0, 1, 3}) {
        StopAfter stop(calls);
        EXPECT_EQ(nonbloppy_test::messageOf<nonbloppy::CancelledError>([&] { nonbloppy::meshToLevelSet(cube, 0.02, 3.0f, &stop); }),
                  "interrupted during mesh to level set")
            << calls;
    }
    StopAfter never(1 << 30);
    const openvdb::FloatGrid::Ptr asked = nonbloppy::meshToLevelSet(cube, 0.02, 3.0f, &never);
    const openvdb::FloatGrid::Ptr plain = nonbloppy::meshToLevelSet(cube, 0.02);
    EXPECT_LT(never.remaining.load(), 1 << 30);  // it was asked
    ASSERT_EQ(asked->activeVoxelCount(), plain->activeVoxelCount());
    auto accessor = plain->getConstAccessor();
    for (auto value = asked->cbeginValueOn(); value; ++value) ASSERT_EQ(*value, accessor.getValue(value.getCoord()));
}
