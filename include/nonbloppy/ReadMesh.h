// SPDX-License-Identifier: Apache-2.0
/// @file ReadMesh.h
/// @brief Read back a polygon mesh (OBJ, PLY with faces, legacy VTK POLYDATA), for
///        `nonbloppy inspect` and for tests that check what writeMesh() wrote.

#ifndef NONBLOPPY_READ_MESH_H
#define NONBLOPPY_READ_MESH_H

#include <nonbloppy/Mesh.h>

#include <string>

namespace nonbloppy {

/// Read the polygons of @a path: triangles and quads are kept, larger polygons are fanned
/// into triangles. Vertex normals are read when present.
/// @throw FileError for a missing, truncated or corrupt file or an unknown extension.
SurfaceMesh readMesh(const std::string& path);

} // namespace nonbloppy

#endif // NONBLOPPY_READ_MESH_H
