// SPDX-License-Identifier: Apache-2.0
/// @file Mesh.h
/// @brief SurfaceMesh, the polygon mesh every stage after extraction reads and writes.

#ifndef NONBLOPPY_MESH_H
#define NONBLOPPY_MESH_H

#include <openvdb/openvdb.h>

#include <string>
#include <vector>

namespace nonbloppy {

/// The largest magnitude up to which every integer is exact as a MeshAttribute value
/// (float32): 2^24. Ids beyond it may round to a neighbour's.
constexpr float kMaxExactAttributeInteger = 16777216.0f;

/// A per-vertex attribute carried by a mesh (e.g. "velocity" interpolated from the
/// particles): values[i * components + c] is component c of vertex i.
struct MeshAttribute
{
    std::string name;            ///< as the particles' attribute, e.g. "velocity"
    int components = 1;          ///< 1 for scalars, 3 for vectors, ...
    std::vector<float> values;   ///< points.size() × components values, vertex-major
    /// The values count or name things (ids, flags: an integer particle attribute, which
    /// interpolateAttributes() carries as the nearest particle's value). writeMesh() then
    /// stores them as 32-bit integers if every one is a whole number within
    /// ±kMaxExactAttributeInteger (beyond, they may have been rounded: floats then).
    bool integer = false;
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
