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
/// A vertex no polygon uses, or whose normals cancel, gets (0,0,0); so does one whose
/// polygons all have zero area, as a droplet's do when c = 1 collapses it to its particle
/// (radius (1 − c)^t r), which covers no pixel when rendered.
/// Cost: O(P + V), in parallel over ranges of 32,768 vertex numbers, each summing the
/// polygons that touch it; deterministic (each vertex sums its polygons in polygon order, so
/// the bits do not depend on the ranges or the thread count). When polygon order and vertex
/// order do not follow each other (a polygon block would reach more than three ranges on
/// average), one serial sum. Memory: the normals, plus 768 KB scratch per thread (24 bytes
/// per vertex in the serial case).
/// @param mesh         normals written
/// @param interrupter  optional; asked every 1024 polygons (no start()/end(): buildSurface()
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
