// SPDX-License-Identifier: Apache-2.0
/// @file ReadMesh.h
/// @brief Read back a polygon mesh (OBJ, PLY with faces, legacy VTK POLYDATA), for
///        `nonbloppy inspect` and for tests that check what writeMesh() wrote.

#ifndef NONBLOPPY_READ_MESH_H
#define NONBLOPPY_READ_MESH_H

#include <nonbloppy/Export.h>
#include <nonbloppy/Mesh.h>

#include <string>

namespace nonbloppy {

/// Read the polygons of @a path: triangles and quads are kept, larger polygons are fanned
/// into triangles (v0, vi, vi+1). Vertex normals are read when present: PLY nx ny nz, VTK
/// NORMALS, OBJ vn (OBJ normals belong to face corners; each vertex gets the normal of the
/// last corner naming it). OBJ faces may use v, v/vt, v//vn and v/vt/vn, and negative
/// (relative) indices.
/// An OBJ file without statements (an empty file) is an empty mesh, as writeMesh() writes
/// one; an OBJ file holding a NUL byte is refused as binary.
/// @throw FileError for a missing, truncated or corrupt file, an unknown extension, a
///        polygon with fewer than three vertices or a vertex index out of range.
/// Cost: one pass over the file. Thread-safety: reentrant, no shared state.
NONBLOPPY_API SurfaceMesh readMesh(const std::string& path);

/// Whether @a path is a mesh by its own declaration, however broken its data: an OBJ file,
/// a PLY file whose header declares at least one face, or a legacy VTK file with a
/// POLYGONS section header of at least one polygon; also an empty mesh as writeMesh()
/// writes one (no vertices, and an empty face element or POLYGONS section). PLY and VTK hold particles too; this
/// tells a broken mesh (for readMesh() to report) from a particle file, which a failing
/// readMesh() cannot.
/// @throw FileError if the file cannot be opened. Cost: PLY reads the header, VTK decodes
///        the file up to its POLYGONS section. Thread-safety: reentrant.
NONBLOPPY_API bool declaresPolygons(const std::string& path);

} // namespace nonbloppy

#endif // NONBLOPPY_READ_MESH_H
