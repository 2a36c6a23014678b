// SPDX-License-Identifier: Apache-2.0
/// @file MeshToLevelSet.cc
/// @brief The surface mesh as a narrow-band level set, via tools::meshToLevelSet.

#include <nonbloppy/Error.h>
#include <nonbloppy/MeshToLevelSet.h>
#include <nonbloppy/ParticleIndex.h>

#include "OpenVdbScale.h"
#include "ParameterChecks.h"
#include "PolygonIndices.h"

#pragma GCC visibility push(default)  // OpenVDB templates: see src/VisibilityPrelude.h
#include <openvdb/tools/MeshToVolume.h>
#pragma GCC visibility pop

#include <cmath>
#include <sstream>

namespace nonbloppy {

openvdb::FloatGrid::Ptr
meshToLevelSet(const SurfaceMesh& mesh, double voxelSize, float halfWidth,
               openvdb::util::NullInterrupter* interrupter)
{
    parameter_checks_internal::requirePositive(voxelSize, "--voxel-size");
    if (!(halfWidth >= 1.0f)) throw ParameterError("level set half width must be >= 1 voxel");
    // Below it OpenVDB throws its own ArithmeticError, not a nonbloppy::Error.
    openvdb_scale_internal::requireOpenVdbScale(voxelSize, kMinCellSize, "--voxel-size");
    // meshToVolume reads the corners unchecked: an index out of range crashed.
    polygon_indices_internal::requireValidIndices(mesh);
    openvdb::initialize();
    const auto transform = openvdb::math::Transform::createLinearTransform(voxelSize);
    // meshToVolume wants index-space points.
    std::vector<openvdb::Vec3s> indexPoints(mesh.points.size());
    for (size_t i = 0; i < indexPoints.size(); ++i) {
        indexPoints[i] = openvdb::Vec3s(transform->worldToIndex(openvdb::Vec3d(mesh.points[i])));
    }
    // Quads are split into two triangles each (the distance field does not care).
    std::vector<openvdb::Vec3I> triangles = mesh.triangles;
    triangles.reserve(mesh.triangles.size() + 2 * mesh.quads.size());
    for (const openvdb::Vec4I& q : mesh.quads) {
        triangles.emplace_back(q[0], q[1], q[2]);
        triangles.emplace_back(q[0], q[2], q[3]);
    }
    // Unlike volumeToMesh, meshToVolume is built to be stopped: it cancels its voxelization
    // tasks, merges what they made and returns that partial grid, which is dropped here.
    openvdb::util::NullInterrupter never;
    openvdb::FloatGrid::Ptr grid = openvdb::tools::meshToVolume<openvdb::FloatGrid>(
        interrupter ? *interrupter : never,
        openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I>(indexPoints, triangles),
        *transform, halfWidth, halfWidth);
    if (interrupter && interrupter->wasInterrupted()) throw CancelledError("interrupted during mesh to level set");
    grid->setName("surface");
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    return grid;
}

} // namespace nonbloppy
