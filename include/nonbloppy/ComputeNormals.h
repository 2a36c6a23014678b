// SPDX-License-Identifier: Apache-2.0
/// @file ComputeNormals.h
/// @brief Stage "compute normals": area-weighted vertex normals.

#ifndef NONBLOPPY_COMPUTE_NORMALS_H
#define NONBLOPPY_COMPUTE_NORMALS_H

#include <nonbloppy/Export.h>
#include <nonbloppy/Mesh.h>

#include <openvdb/util/NullInterrupter.h>

namespace nonbloppy {

/// Set mesh.normals[i] to the normalized sum of the area-weighted normals of the polygons
/// around vertex i (a quad's normal is half the cross product of its diagonals).
/// A vertex no polygon uses, or whose normals cancel, gets (0,0,0).
/// Cost: O(P + V); deterministic (sums in polygon order). Memory: 24 bytes per vertex scratch.
/// @param mesh         normals written
/// @param interrupter  optional; asked every 4096 polygons of the serial sum and every 4096
///                     vertices of each parallel task (no start()/end(): buildSurface()
///                     announces the stage); a stop leaves mesh.normals unspecified
/// Thread-safety: reentrant; concurrent calls on different meshes are safe.
/// @throw ParameterError("polygon P references vertex I but the mesh has N vertices") for
///        the first polygon (triangles first, then quads) with a corner out of range, and
///        mesh.normals is then untouched; CancelledError("interrupted during compute
///        normals") when @a interrupter says stop; otherwise nothing but std::bad_alloc.
NONBLOPPY_API void computeNormals(SurfaceMesh& mesh,
                                  openvdb::util::NullInterrupter* interrupter = nullptr);

} // namespace nonbloppy

#endif // NONBLOPPY_COMPUTE_NORMALS_H
