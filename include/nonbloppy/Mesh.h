// SPDX-License-Identifier: Apache-2.0
/// @file Mesh.h
/// @brief SurfaceMesh, the polygon mesh every stage after extraction reads and writes.

#ifndef NONBLOPPY_MESH_H
#define NONBLOPPY_MESH_H

#include <openvdb/openvdb.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace nonbloppy {

/// A per-vertex attribute carried by a mesh (e.g. "velocity" interpolated from the
/// particles). A quantity (velocity, temperature) is held as floats; one that counts or
/// names things (ids, flags, material indices: an integer particle attribute, which
/// interpolateAttributes() carries as the nearest particle's value) as exact 64-bit
/// integers, so an id past 2^24, where floats skip integers, stays the particle's.
/// Either way, element i * components + c is component c of vertex i.
struct MeshAttribute
{
    std::string name;                ///< as the particles' attribute, e.g. "velocity"
    int components = 1;              ///< 1 for scalars, 3 for vectors, ...
    /// Which of the two arrays holds the values; the other stays empty. writeMesh() stores
    /// integers in the narrowest type of the format that holds every one (see there).
    bool integer = false;
    std::vector<float> values;       ///< points.size() × components floats, unless integer
    std::vector<int64_t> integers;   ///< points.size() × components integers, if integer

    /// Number of values held, whichever array holds them.
    size_t size() const { return integer ? integers.size() : values.size(); }
    /// Element @a i (vertex i / components, component i % components) as a double, exact
    /// for floats and for integers within ±2^53.
    double asDouble(size_t i) const { return integer ? double(integers[i]) : double(values[i]); }
};

/// A polygon mesh of triangles and quads sharing one vertex array, in world units.
/// Polygons run counter-clockwise seen from outside the fluid, so the right-hand-rule
/// face normal points out of the fluid. Quads are kept as volumeToMesh made them;
/// writers split them into triangles where asked or where the format needs it.
struct SurfaceMesh
{
    std::vector<openvdb::Vec3s> points;     ///< vertex positions, world units
    std::vector<openvdb::Vec3s> normals;    ///< unit vertex normals; empty until computeNormals()
    std::vector<openvdb::Vec3I> triangles;  ///< vertex indices, counter-clockwise from outside
    std::vector<openvdb::Vec4I> quads;      ///< vertex indices, counter-clockwise from outside
    std::vector<MeshAttribute> attributes;  ///< per-vertex values; see interpolateAttributes()

    /// Number of polygons, triangles plus quads.
    size_t polygonCount() const { return triangles.size() + quads.size(); }
    /// Number of triangles after splitting every quad in two.
    size_t triangleCount() const { return triangles.size() + 2 * quads.size(); }
};

} // namespace nonbloppy

#endif // NONBLOPPY_MESH_H
