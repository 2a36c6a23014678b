// SPDX-License-Identifier: Apache-2.0
/// @file PolygonIndices.h
/// @brief Private: a polygon's corners by its number, and the one check that a mesh's
///        polygons reference only its vertices, with its message. Only src/ includes it.

#ifndef NONBLOPPY_POLYGON_INDICES_H
#define NONBLOPPY_POLYGON_INDICES_H

#include <nonbloppy/Mesh.h>

#include <cstdint>
#include <string>
#include <utility>

namespace nonbloppy {
namespace polygon_indices_internal {

/// The corners of polygon @a polygon of @a mesh, numbered as the writers number them
/// (triangles first, then quads): a pointer to its vertex indices and their count, 3 or 4.
inline std::pair<const uint32_t*, int> cornersOf(const SurfaceMesh& mesh, size_t polygon)
{
    const size_t triangleCount = mesh.triangles.size();
    return polygon < triangleCount ? std::make_pair(mesh.triangles[polygon].asPointer(), 3)
                                   : std::make_pair(mesh.quads[polygon - triangleCount].asPointer(), 4);
}

/// "polygon P references vertex I but the mesh has N vertices".
std::string badIndexMessage(size_t polygon, uint32_t index, size_t vertexCount);

/// badIndexMessage() for the first polygon of @a mesh (triangles first, then quads, as the
/// writers number them) with a corner out of range, or "" if there is none. Cost: O(P), in
/// parallel (the mesh's largest pass before writeMesh() writes a byte: 17 ms serially for
/// 2.4M quads). Defined in MeasureMesh.cc.
std::string firstBadIndex(const SurfaceMesh& mesh);

/// Throw ParameterError(firstBadIndex(mesh)) if a polygon of @a mesh has a corner out of
/// range: the check every public mesh stage makes before it reads a corner. Cost: as
/// firstBadIndex().
void requireValidIndices(const SurfaceMesh& mesh);

} // namespace polygon_indices_internal
} // namespace nonbloppy

#endif // NONBLOPPY_POLYGON_INDICES_H
