// SPDX-License-Identifier: Apache-2.0
/// @file ReadParticles.h
/// @brief Stage "read particles": load a particle file into a ParticleSet.
///
/// Formats, chosen by the file extension (case-insensitive):
/// - `.vtk`  legacy VTK (ASCII or binary big-endian, versions up to 5.1), UNSTRUCTURED_GRID
///           or POLYDATA, float or double POINTS (stored as float). Cell sections are
///           skipped (both the count-prefixed layout and VTK 5's OFFSETS/CONNECTIVITY), as
///           are CELL_DATA, dataset-level FIELD data and METADATA blocks. Every POINT_DATA
///           array (SCALARS, VECTORS, NORMALS, TENSORS, TEXTURE_COORDINATES, COLOR_SCALARS,
///           FIELD arrays) becomes an attribute in its stored type; `long` is read as 64-bit
///           and `vtkIdType` as 32-bit, as VTK's legacy writer stores them. Names written
///           with %XX escapes (VTK 5) are decoded.
/// - `.ply`  PLY (ascii, binary_little_endian, binary_big_endian); vertex x y z (float or
///           double) plus every other scalar vertex property as an attribute in its type;
///           consecutive properties `name_x/_y/_z` or `name_0, name_1, ...` of one type form
///           one vector `name` (as writeParticles() writes vectors), unless a property is
///           itself called `name`; list properties and other elements are skipped.
/// - `.xyz`  raw little-endian float32 triples, no header.
/// - `.bgeo` Houdini classic binary geometry (`BgeoV` version 5, as Partio and SPlisHSPlasH
///           write it), gzip-compressed or not; float, int, vector and index point
///           attributes. Also under `.bhclassic`, the name Houdini 12 and later write that
///           layout under, and gzipped as `.bgeo.gz` or `.bhclassic.gz`. Houdini's own
///           `.bgeo` (and `.bgeo.gz`) is JSON-based and rejected as unsupported, as are
///           `.bgeo.sc` (Blosc) and the ASCII `.geo`; the messages name `.bhclassic` instead.
/// - `.vtu`, `.vtp`  VTK XML UnstructuredGrid / PolyData: ascii, inline base64 and appended
///           (raw or base64) arrays, zlib-compressed or not, UInt32/UInt64 headers, either
///           byte order, Float32/Float64 points; every PointData array in its type.
/// - `.vdb`  the first openvdb::points::PointDataGrid: world positions from `P` plus every
///           numeric, vector, quaternion (4 components) and matrix attribute (9 or 16,
///           row by row); group and string attributes are skipped. The scalars
///           `name_0, name_1, ...` that writeParticles() splits an attribute into (OpenVDB has
///           no type for 2 or 4 components, say; it lists them in the grid's metadata
///           "nonbloppy_split_attributes") form one attribute `name` again; other scalars keep
///           their names. A .vdb without a PointDataGrid (e.g. a density cache) is an error.
/// - `.csv`, `.txt`  a header row naming the columns (x, y, z or ParaView's Points:0..2,
///           plus any others; consecutive `name:0, name:1, ...` (up to 100), `name[0], ...`,
///           `name_x/_y/_z` or `name.x/.y/.z` form a vector `name` unless a column is itself
///           called `name`; a lone `name_x` keeps its name; `name_0` is a scalar),
///           separated by ',', ';', tabs or spaces, names and values optionally quoted
///           (in double quotes a doubled quote is one: `"e""f"` names `e"f`, RFC 4180);
///           a column without a name (pandas' and R's row numbers) is left out and listed in
///           ParticleSet::skipped; attributes are int64 if every value is an integer that
///           fits, uint64 if none is negative and some pass int64, else float64.
/// - `.json` `[[x, y, z], ...]` (positions only).
/// A file with zero particles is read without complaint (the pipeline rejects it later).
/// Cost: one pass over the file. `.vtk`, `.ply`, `.xyz`, `.bgeo` (gzip inflated in chunks),
/// `.csv`/`.txt` and `.json` are streamed: headers and text go through a 1 MiB buffer, and
/// binary arrays are read from the file straight into the final position and attribute
/// arrays (then byte-swapped in place if needed), so memory is the particle set plus that
/// buffer (12 bytes per particle for x y z; about 0.35 s for 12.5M binary PLY particles).
/// `.vtu`/`.vtp` (an XML document, parsed by expat in chunks; appended raw arrays read
/// straight into the final arrays) and `.vdb` (OpenVDB reading through a 64 KB stream
/// buffer; peak memory the PointDataGrid, then the particle arrays) are streamed too.
/// Text is parsed with std::from_chars; no per-particle heap objects. Every count in a
/// header is checked against the bytes left in the file (its size) before allocating.
/// Pipes, whose size is unknown, are read whole first.

#ifndef NONBLOPPY_READ_PARTICLES_H
#define NONBLOPPY_READ_PARTICLES_H

#include <nonbloppy/Export.h>
#include <nonbloppy/Particles.h>

#include <string>

namespace nonbloppy {

/// Read every particle and per-particle attribute of @a path.
/// @throw FileError  for a missing, unreadable, truncated or corrupt file, an unknown
///                   extension, or more particles than the memory this process can still
///                   take (checked before the arrays are allocated); one line naming @a path,
///                   e.g. "cannot open x.vtk: No such file or directory",
///                   "truncated POINTS section (x.vtk)", "8000000000 particles would take
///                   96 GB of memory, more than the 25.2 GB this process can still take (x.ply)".
/// @throw ParameterError  for NaN or infinite coordinates, or doubles too large for float:
///                   "non-finite position of particle 17 (x.vtk)"; in CSV and JSON text, a
///                   finite coordinate beyond float is a FileError quoting it ("coordinate
///                   1e39 on line 3 lies outside float's range (-3.4e38 to 3.4e38) (x.csv)").
/// Thread-safe: yes (no shared state).
NONBLOPPY_API ParticleSet readParticles(const std::string& path);

/// True if @a path has an extension readParticles() understands (`.bhclassic`, `.bgeo.gz`
/// and `.bhclassic.gz` included).
NONBLOPPY_API bool isParticleFile(const std::string& path);

/// Refuses @a path as readParticles() would, by its extension alone, before any file is
/// opened (so a caller can check a name given on a command line, or a frame pattern).
/// Cost: O(length of @a path).
/// @throw FileError "particle file name has no extension (x); expected .vtk, ...", or
///        "unknown particle file extension '.foo' (x.foo); expected .vtk, ..."; for Houdini's
///        JSON caches (`.bgeo.sc`, ...) the message says which name to export instead.
NONBLOPPY_API void requireParticleFile(const std::string& path);

} // namespace nonbloppy

#endif // NONBLOPPY_READ_PARTICLES_H
