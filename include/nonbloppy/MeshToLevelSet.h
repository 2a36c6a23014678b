// SPDX-License-Identifier: Apache-2.0
/// @file MeshToLevelSet.h
/// @brief Stage "mesh to level set": the final surface as a narrow-band signed distance
///        grid (openvdb::tools::meshToVolume), for renderers and tools that take level sets.

#ifndef NONBLOPPY_MESH_TO_LEVEL_SET_H
#define NONBLOPPY_MESH_TO_LEVEL_SET_H

#include <nonbloppy/Export.h>
#include <nonbloppy/Mesh.h>

#include <openvdb/openvdb.h>

namespace nonbloppy {

/// A FloatGrid named "surface", class GRID_LEVEL_SET, holding the signed distance (world
/// units, negative inside) to @a mesh within @a halfWidth voxels of it, voxel size
/// @a voxelSize world units. The mesh should be closed; holes leak the inside sign.
/// Cost: O(polygons · halfWidth³), parallel inside OpenVDB.
/// @throw ParameterError if voxelSize ≤ 0 or below kMinCellSize, halfWidth < 1, or a
///        polygon references a vertex the mesh does not have ("polygon P references vertex
///        I but the mesh has N vertices", polygons numbered triangles first, then quads).
NONBLOPPY_API openvdb::FloatGrid::Ptr meshToLevelSet(const SurfaceMesh& mesh, double voxelSize,
                                       float halfWidth = 3.0f);

} // namespace nonbloppy

#endif // NONBLOPPY_MESH_TO_LEVEL_SET_H
