// SPDX-License-Identifier: Apache-2.0
/// @file MeasureMesh.h
/// @brief Topology and geometry measures of a SurfaceMesh: closed, manifold, area, volume.

#ifndef NONBLOPPY_MEASURE_MESH_H
#define NONBLOPPY_MEASURE_MESH_H

#include <nonbloppy/Export.h>
#include <nonbloppy/Mesh.h>

#include <cstddef>

namespace nonbloppy {

/// What measureMesh() finds.
struct MeshMeasures
{
    size_t vertices = 0;          ///< mesh.points.size()
    size_t polygons = 0;          ///< triangles + quads
    size_t unusedVertices = 0;    ///< vertices no polygon references
    size_t nonFiniteVertices = 0; ///< vertices with a NaN or infinite coordinate
    size_t zeroAreaPolygons = 0;  ///< polygons of zero area: collapsed (c = 1 shrinks a
                                  ///< droplet to a point) or with a corner repeated
    size_t boundaryEdges = 0;     ///< edges with one adjacent polygon
    size_t nonManifoldEdges = 0;  ///< edges with three or more adjacent polygons
    size_t inconsistentEdges = 0; ///< edges of two polygons that both use it in the same
                                  ///< direction (one of them is flipped)
    bool closed = false;          ///< at least one polygon and no boundary edges
    bool manifold = false;        ///< every edge has exactly two polygons, oriented
                                  ///< consistently (so an open mesh is not manifold here)
    double area = 0.0;            ///< world units²
    double volume = 0.0;          ///< signed enclosed volume (divergence theorem), world units³;
                                  ///< positive when polygons face outwards
};

/// Measure @a mesh (quads split into two triangles for area and volume; edges joining a
/// vertex to itself, from degenerate polygons, are not counted). Edge checks only: two
/// surfaces touching at a single vertex are not detected as non-manifold.
/// Cost: O(P) for P polygons: each edge is filed under its lower vertex (a counting sort) and
/// each vertex's few edges are sorted; in parallel but for the area and volume, summed in
/// polygon order (the same result for any thread count). Scratch: 8 bytes per polygon corner
/// and 13 per vertex. `nonbloppy inspect` of the 64x benchmark mesh (4.74M triangles, two
/// threads) takes 0.97 s, 1.64 s when all edges were listed and sorted serially.
/// Thread-safety: reentrant; the mesh is only read.
/// @throw ParameterError if a polygon references a vertex index out of range.
NONBLOPPY_API MeshMeasures measureMesh(const SurfaceMesh& mesh);

/// Area and signed enclosed volume of a mesh.
struct AreaAndVolume
{
    double area = 0.0;    ///< world units²
    double volume = 0.0;  ///< world units³, positive when polygons face outwards
};

/// The area and volume that measureMesh() reports (it calls this), without its edge
/// topology: what a volume correction asks on every pass.
/// Cost: O(P), serial, no scratch memory: about 0.02 s on a 2.4M-vertex mesh (measureMesh()
/// also files every edge). Thread-safety: reentrant; the mesh is only read.
/// @throw ParameterError if a polygon references a vertex index out of range (as measureMesh()).
NONBLOPPY_API AreaAndVolume measureAreaAndVolume(const SurfaceMesh& mesh);

} // namespace nonbloppy

#endif // NONBLOPPY_MEASURE_MESH_H
