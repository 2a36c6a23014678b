// SPDX-License-Identifier: Apache-2.0
/// @file WriteMesh.h
/// @brief Stage "write mesh": save a SurfaceMesh as OBJ, binary PLY or legacy VTK polydata.

#ifndef NONBLOPPY_WRITE_MESH_H
#define NONBLOPPY_WRITE_MESH_H

#include <nonbloppy/Export.h>
#include <nonbloppy/Mesh.h>

#include <string>
#include <vector>

namespace nonbloppy {

/// How a mesh is written.
struct MeshWriteSettings
{
    /// Keep quads as quads (OBJ, PLY and VTK all allow them); false splits every quad
    /// (q0,q1,q2,q3) into triangles (q0,q1,q2) and (q0,q2,q3).
    bool keepQuads = false;
    /// Write files of 1 MiB or more with direct I/O (O_DIRECT, past the page cache) on
    /// local ext4, XFS or Btrfs disks; other file systems, and false, use the page cache.
    /// The bytes are the same. A mesh is written once and read by another program, so
    /// caching it only costs: on the benchmark machine the 119 MB mesh of the 64x input took
    /// 0.09–0.11 s direct and 0.08–0.78 s through the page cache, whose flush then ran on
    /// into the next run (write stage, alternating pairs, 2026-12-05).
    bool directIo = true;
};

/// Write @a mesh to @a path; the format follows the extension: `.obj` (v, vn, f; 1-based),
/// `.ply` (binary little-endian: float x y z, float nx ny nz when normals exist, uchar-count
/// int faces), `.vtk` (legacy binary POLYDATA, POINTS float, POLYGONS, POINT_DATA NORMALS).
/// The file is written to a temporary file beside @a path and renamed into place, so a
/// failed or interrupted write never leaves a partial file.
/// Output is byte-identical for identical meshes: OBJ coordinates use the shortest decimal
/// text that reads back as the same float (std::to_chars), and nothing depends on time.
/// Normals are written only when mesh.normals is non-empty; PLY and VTK also declare them
/// (with no values) for a mesh without vertices, so that the empty frames of a sequence
/// declare the columns its other frames have.
/// Per-vertex attributes (mesh.attributes, see interpolateAttributes()) are written as PLY
/// float vertex properties ("density"; a 3-vector "velocity" as velocity_x, velocity_y,
/// velocity_z) and as VTK POINT_DATA (VECTORS for 3 components, SCALARS for 1, 2 or 4, a
/// FIELD array otherwise). Integer attributes (MeshAttribute::integer: ids) are written
/// exactly, as PLY int, else uint, where every value fits, else double (exact within
/// ±2^53, as PLY has no 64-bit type), and as VTK int, else vtktypeint64. OBJ has no place
/// for attributes: they are left out. Names are written as writeParticles() writes them
/// (whitespace, control and non-ASCII bytes, ',', '"', '<', '>' and '&' become '_') and
/// kept distinct from one another and from the format's own columns (PLY x, y, z and,
/// with normals, nx, ny, nz; the VTK normals array "normals"): such a name gets _2, _3,
/// ... (writtenAttributeNames() tells which).
/// Cost: one pass, parallel: PLY and VTK records are encoded in 8 MB batches, OBJ lines
/// formatted in pieces of 4096, and written in order while the next are encoded (the bytes
/// do not depend on the thread count). The 64x benchmark mesh (2.39M vertices, 4.74M
/// triangles, two threads): PLY (119 MB) about 0.1 s, OBJ (403 MB of text) about 0.43 s.
/// Thread-safety: reentrant; concurrent calls must write different paths.
/// @throw FileError for an unknown extension or a file that cannot be written, e.g.
///        "cannot write out/mesh.obj: No such file or directory"; nothing is left behind.
///        PLY and VTK, whose indices are 32-bit, refuse a mesh with more than 2³¹ − 1
///        vertices or polygon corners ("too many vertices for 32-bit indices (PATH)").
/// @throw ParameterError if a polygon references a vertex that does not exist,
///        mesh.normals is non-empty but not one per vertex, or an attribute has fewer than
///        one component (more than 4096, the most the readers take, for PLY and VTK), not
///        V·components values, or values in the array its MeshAttribute::integer flag
///        does not name.
NONBLOPPY_API void writeMesh(const SurfaceMesh& mesh, const std::string& path,
               const MeshWriteSettings& settings = MeshWriteSettings());

/// The names writeMesh() gives @a mesh's attributes in @a path's format, one per attribute
/// in order (a PLY vector's properties add _x, _y, _z, other multi-component ones _<c>);
/// empty strings for `.obj`, which leaves attributes out. Compare with
/// MeshAttribute::name to tell a caller what was renamed.
/// Cost: O(A log A) for A attributes; reads no vertex data.
/// @throw FileError for an unknown extension, as writeMesh().
NONBLOPPY_API std::vector<std::string> writtenAttributeNames(const SurfaceMesh& mesh, const std::string& path);

/// The names of @a mesh's integer attributes that writeMesh() stores rounded in @a path's
/// format: in PLY, which has no 64-bit integer, those with a value past ±2^53 (written as
/// doubles). Empty for `.vtk` (vtktypeint64 keeps them) and `.obj` (no attributes).
/// Cost: one pass over the integer attributes' values, until one is past 2^53.
/// @throw FileError for an unknown extension, as writeMesh().
NONBLOPPY_API std::vector<std::string> roundedAttributes(const SurfaceMesh& mesh, const std::string& path);

/// True if @a path has an extension writeMesh() understands.
NONBLOPPY_API bool isMeshFile(const std::string& path);

/// Refuses @a path as writeMesh() would, by its extension alone, so that a caller can check
/// an output name before the work that leads to it. Cost: O(length of @a path).
/// @throw FileError "mesh file name has no extension (out); expected .obj, .ply or .vtk", or
///        "unknown mesh file extension '.stl' (out.stl); expected .obj, .ply or .vtk"
NONBLOPPY_API void requireMeshFile(const std::string& path);

} // namespace nonbloppy

#endif // NONBLOPPY_WRITE_MESH_H
