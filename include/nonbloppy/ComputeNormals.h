// SPDX-License-Identifier: Apache-2.0
/// @file ComputeNormals.h
/// @brief Stage "compute normals": area-weighted vertex normals.

#ifndef NONBLOPPY_COMPUTE_NORMALS_H
#define NONBLOPPY_COMPUTE_NORMALS_H

#include <nonbloppy/Export.h>
#include <nonbloppy/Mesh.h>

namespace nonbloppy {

/// Set mesh.normals[i] to the normalized sum of the area-weighted normals of the polygons
/// around vertex i (a quad's normal is half the cross product of its diagonals).
/// A vertex no polygon uses, or whose normals cancel, gets (0,0,0).
/// Cost: O(P + V); deterministic (sums in polygon order). Memory: 24 bytes per vertex scratch.
/// Thread-safety: reentrant; concurrent calls on different meshes are safe. Throws nothing
/// but std::bad_alloc; polygon indices must be valid (see measureMesh() to check them).
NONBLOPPY_API void computeNormals(SurfaceMesh& mesh);

} // namespace nonbloppy

#endif // NONBLOPPY_COMPUTE_NORMALS_H
