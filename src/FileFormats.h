// SPDX-License-Identifier: Apache-2.0
/// @file FileFormats.h
/// @brief Private parsers shared by readParticles() and readMesh(): whole-file loading, a
///        bounds-checked text cursor, and legacy VTK and PLY decoders that return plain
///        arrays. Nothing here is public API.
///
/// Every parser works on a buffer holding the whole file, checks every count against the
/// bytes left before allocating, and reports problems as one-line FileErrors ending in
/// "(<path>)", so no byte sequence can make it crash, hang or allocate without bound.

#ifndef NONBLOPPY_FILE_FORMATS_H
#define NONBLOPPY_FILE_FORMATS_H

#include <nonbloppy/Particles.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace nonbloppy {
namespace io_internal {

/// The whole contents of @a path.
/// @throw FileError "cannot open <path>: <reason>" or "cannot read <path>: <reason>".
std::vector<char> loadFile(const std::string& path);

/// The extension of the last path component, lower-cased, with its dot (".vtk"), or "".
std::string lowerExtension(const std::string& path);

/// Throw FileError("<what> (<path>)").
[[noreturn]] void fail(const std::string& path, const std::string& what);

/// @a text made safe for a one-line message: at most 40 characters, non-printable bytes
/// replaced by '?'.
std::string printable(std::string_view text);

/// One array of values from a file, converted to native byte order but kept in its type.
struct NumericArray
{
    std::string name;
    std::string kind;      ///< VTK section it came from ("SCALARS", "NORMALS", "FIELD", ...)
    ScalarType type = ScalarType::Float32;
    int components = 1;
    std::vector<unsigned char> bytes;  ///< tuples × components values
};

/// Polygons as offsets into a flat index list: polygon i uses
/// indices[offsets[i]] ... indices[offsets[i+1]-1].
struct PolygonList
{
    std::vector<size_t> offsets{0};
    std::vector<uint32_t> indices;
    size_t size() const { return offsets.size() - 1; }
};

/// What parseVtk() found in a legacy VTK file.
struct VtkData
{
    std::vector<openvdb::Vec3f> points;       ///< POINTS (double converted to float)
    std::vector<NumericArray> pointArrays;    ///< every POINT_DATA array, in file order
    PolygonList polygons;                     ///< POLYGONS, only if asked for
};

/// Decode a legacy VTK file (ASCII or big-endian BINARY; version 2 to 5.1 cell layouts;
/// DATASET UNSTRUCTURED_GRID or POLYDATA). Cell sections are skipped unless
/// @a wantPolygons, in which case POLYGONS are kept.
VtkData parseVtk(const char* data, size_t size, const std::string& path, bool wantPolygons);

/// What parsePly() found in a PLY file.
struct PlyData
{
    size_t vertexCount = 0;
    std::vector<NumericArray> vertexProperties;  ///< scalar vertex properties, 1 component each
    PolygonList faces;                           ///< face vertex_indices, only if asked for
};

/// Decode a PLY file (ascii, binary_little_endian or binary_big_endian).
/// List properties of the vertex element, and every other element, are skipped, except
/// the face element's vertex_indices (or vertex_index) list when @a wantFaces.
PlyData parsePly(const char* data, size_t size, const std::string& path, bool wantFaces);

/// The values of a 1- or 3-component array as floats (for positions and normals).
std::vector<float> toFloats(const NumericArray& array);

} // namespace io_internal
} // namespace nonbloppy

#endif // NONBLOPPY_FILE_FORMATS_H
