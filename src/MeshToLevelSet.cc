// SPDX-License-Identifier: Apache-2.0
/// @file MeshToLevelSet.cc
/// @brief The surface mesh as a narrow-band level set, via tools::meshToLevelSet.

#include <nonbloppy/Error.h>
#include <nonbloppy/MeasureMesh.h>
#include <nonbloppy/MeshToLevelSet.h>
#include <nonbloppy/ParticleIndex.h>

#include "MachineMemory.h"
#include "OpenVdbScale.h"
#include "ParameterChecks.h"

#pragma GCC visibility push(default)  // OpenVDB templates: see src/VisibilityPrelude.h
#include <openvdb/tools/MeshToVolume.h>
#pragma GCC visibility pop

#include <algorithm>
#include <cmath>
#include <sstream>

namespace nonbloppy {

namespace {

/// Peak memory per voxel of the narrow band while meshToVolume runs (the distance grid, its
/// polygon-index grid and scratch): 19–30 bytes measured on the dam-break surface at h/2 and
/// h/4 with half widths 3 and 10, rounded up.
constexpr double kPeakBytesPerBandVoxel = 32.0;

/// @throw ParameterError naming the first vertex that is not finite, or the largest
///        coordinate if it is too far from the origin for 32-bit voxel coordinates.
void requireVerticesInRange(const SurfaceMesh& mesh, double voxelSize, float halfWidth)
{
    float largest = 0.0f;
    for (size_t i = 0; i < mesh.points.size(); ++i) {
        const openvdb::Vec3s& p = mesh.points[i];
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
            throw ParameterError("non-finite position of vertex " + std::to_string(i));
        }
        largest = std::max({largest, std::abs(p[0]), std::abs(p[1]), std::abs(p[2])});
    }
    openvdb_scale_internal::requireIndexRange(double(largest), voxelSize, "mesh", "voxel size", double(halfWidth));
}

/// @throw ParameterError if the narrow band (the surface's area in voxels times 2·halfWidth,
///        within 8% of the active voxels counted on the dam-break surface) would need more
///        memory than the process can still take (memoryHeadroomBytes()): meshToVolume's
///        std::bad_alloc ends the process.
void requireBandFitsInMemory(double area, double voxelSize, float halfWidth)
{
    const double bandVoxels = area / (voxelSize * voxelSize) * 2.0 * double(halfWidth);
    const double needed = bandVoxels * kPeakBytesPerBandVoxel, available = machine_memory_internal::memoryHeadroomBytes();
    if (available >= 0.0 && needed > available) {
        std::ostringstream msg;
        msg.precision(2);
        msg << "the level set's narrow band would hold about " << bandVoxels << " voxels, about "
            << machine_memory_internal::formatBytes(needed) << " at its peak, more than the "
            << machine_memory_internal::formatBytes(available)
            << " this process can still take: use a voxel size larger than " << voxelSize
            << " or a half width below " << halfWidth;
        throw ParameterError(msg.str());
    }
}

} // namespace

openvdb::FloatGrid::Ptr
meshToLevelSet(const SurfaceMesh& mesh, double voxelSize, float halfWidth,
               openvdb::util::NullInterrupter* interrupter)
{
    parameter_checks_internal::requirePositive(voxelSize, "--voxel-size");
    if (!(halfWidth >= 1.0f) || !std::isfinite(halfWidth)) {
        // An infinite band gave an empty grid.
        std::ostringstream msg;
        msg << "level set half width must be >= 1 voxel and finite, got " << halfWidth;
        throw ParameterError(msg.str());
    }
    // Below it OpenVDB throws its own ArithmeticError, not a nonbloppy::Error.
    openvdb_scale_internal::requireOpenVdbScale(voxelSize, kMinCellSize, "--voxel-size");
    requireVerticesInRange(mesh, voxelSize, halfWidth);
    // meshToVolume reads the corners unchecked (an index out of range crashed): the area's
    // serial pass checks them, triangles first, with polygon_indices_internal's message.
    requireBandFitsInMemory(measureAreaAndVolume(mesh).area, voxelSize, halfWidth);
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
