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

/// The vertices' bounding box (BBoxd() without vertices).
/// @throw ParameterError naming the first vertex that is not finite, or the largest
///        coordinate if it is too far from the origin for 32-bit voxel coordinates.
openvdb::BBoxd requireVerticesInRange(const SurfaceMesh& mesh, double voxelSize, float halfWidth)
{
    openvdb::BBoxd bounds;  // empty
    for (size_t i = 0; i < mesh.points.size(); ++i) {
        const openvdb::Vec3s& p = mesh.points[i];
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
            throw ParameterError("non-finite position of vertex " + std::to_string(i));
        }
        bounds.expand(openvdb::Vec3d(p));
    }
    if (mesh.points.empty()) return bounds;
    double largest = 0.0;
    for (int axis = 0; axis < 3; ++axis) {
        largest = std::max({largest, std::abs(bounds.min()[axis]), std::abs(bounds.max()[axis])});
    }
    openvdb_scale_internal::requireIndexRange(largest, voxelSize, "mesh", "voxel size", double(halfWidth));
    return bounds;
}

/// The narrow band's voxels: the surface's area in voxels times 2·halfWidth (within 8% of
/// the active voxels counted on the dam-break surface), plus a ball of halfWidth voxels
/// for the band around the surface's ends and edges, which the area leaves out (one
/// triangle of area 0.005 at h = 1 and half width 60: 0.6 voxels by area, 902,813 made;
/// 904,779 so), at most the mesh's bounding box grown by the band.
double bandVoxelsOf(double area, const openvdb::BBoxd& bounds, double voxelSize, float halfWidth)
{
    const double width = double(halfWidth);
    const double byArea = area / (voxelSize * voxelSize) * 2.0 * width + 4.0 / 3.0 * M_PI * width * width * width;
    const openvdb::Vec3d extent = bounds.extents() / voxelSize + openvdb::Vec3d(2.0 * width + 1.0);
    return std::min(byArea, extent[0] * extent[1] * extent[2]);
}

/// @throw ParameterError if the narrow band (bandVoxelsOf()) would need more memory than
///        the process can still take (memoryHeadroomBytes()): meshToVolume's std::bad_alloc
///        ends the process.
void requireBandFitsInMemory(double area, const openvdb::BBoxd& bounds, double voxelSize, float halfWidth)
{
    const double bandVoxels = bandVoxelsOf(area, bounds, voxelSize, halfWidth);
    const double needed = bandVoxels * kPeakBytesPerBandVoxel;
    machine_memory_internal::requireHeadroom(needed, [&] {
        std::ostringstream need, advice;
        need.precision(2);
        advice.precision(2);
        need << "the level set's narrow band would hold about " << bandVoxels << " voxels, about "
             << machine_memory_internal::formatBytes(needed) << " at its peak";
        advice << "use a voxel size larger than " << voxelSize << " or a half width below " << halfWidth;
        return std::make_pair(need.str(), advice.str());
    });
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
    const openvdb::BBoxd bounds = requireVerticesInRange(mesh, voxelSize, halfWidth);
    // meshToVolume reads the corners unchecked (an index out of range crashed): the area's
    // serial pass checks them, triangles first, with polygon_indices_internal's message.
    const double area = measureAreaAndVolume(mesh).area;
    if (!mesh.points.empty()) requireBandFitsInMemory(area, bounds, voxelSize, halfWidth);
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
