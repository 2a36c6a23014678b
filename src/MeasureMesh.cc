// SPDX-License-Identifier: Apache-2.0
/// @file MeasureMesh.cc
/// @brief Edge topology (boundary, non-manifold, inconsistent), area and signed volume.

#include <nonbloppy/MeasureMesh.h>

#include <nonbloppy/Error.h>

#include "PolygonIndices.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace nonbloppy {

namespace {

/// An undirected edge (low, high) packed into one key, plus the direction it was used in.
struct EdgeUse
{
    uint64_t key;
    bool forward;  ///< used as low → high

    bool operator<(const EdgeUse& other) const
    {
        return key < other.key || (key == other.key && forward < other.forward);
    }
};

void
addEdge(std::vector<EdgeUse>& edges, uint32_t from, uint32_t to)
{
    if (from == to) return;  // a collapsed edge of a degenerate polygon bounds nothing
    const uint32_t low = std::min(from, to), high = std::max(from, to);
    edges.push_back({(uint64_t(low) << 32) | high, from < to});
}

/// Adds the area and the signed volume of the tetrahedron (origin, p0, p1, p2); returns
/// the triangle's area.
double
addTriangle(const SurfaceMesh& mesh, uint32_t i0, uint32_t i1, uint32_t i2, AreaAndVolume& m)
{
    const openvdb::Vec3d p0(mesh.points[i0]), p1(mesh.points[i1]), p2(mesh.points[i2]);
    const double area = 0.5 * (p1 - p0).cross(p2 - p0).length();
    m.area += area;
    // Divergence theorem: the volume is the sum over faces of p0 · (p1 × p2) / 6.
    m.volume += p0.dot(p1.cross(p2)) / 6.0;
    return area;
}

[[noreturn]] void
throwBadIndex(const SurfaceMesh& mesh, size_t polygon, uint32_t index)
{
    throw ParameterError(polygon_indices_internal::badIndexMessage(polygon, index, mesh.points.size()));
}

} // namespace

std::string
polygon_indices_internal::badIndexMessage(size_t polygon, uint32_t index, size_t vertexCount)
{
    return "polygon " + std::to_string(polygon) + " references vertex " + std::to_string(index) +
           " but the mesh has " + std::to_string(vertexCount) + " vertices";
}

std::string
polygon_indices_internal::firstBadIndex(const SurfaceMesh& mesh)
{
    const size_t vertexCount = mesh.points.size();
    const size_t triangleCount = mesh.triangles.size(), polygonCount = triangleCount + mesh.quads.size();
    const auto cornersOf = [&](size_t polygon) {
        return polygon < triangleCount
            ? std::make_pair(mesh.triangles[polygon].asPointer(), 3)
            : std::make_pair(mesh.quads[polygon - triangleCount].asPointer(), 4);
    };
    const auto outOfRange = [&](uint32_t index) { return index >= vertexCount; };
    const size_t bad = tbb::parallel_reduce(tbb::blocked_range<size_t>(0, polygonCount), polygonCount,
        [&](const tbb::blocked_range<size_t>& range, size_t found) {
            for (size_t n = range.begin(); n < range.end() && n < found; ++n) {
                const auto [corners, count] = cornersOf(n);
                if (std::any_of(corners, corners + count, outOfRange)) return n;
            }
            return found;
        },
        [](size_t a, size_t b) { return std::min(a, b); });
    if (bad == polygonCount) return std::string();
    const auto [corners, count] = cornersOf(bad);
    return badIndexMessage(bad, *std::find_if(corners, corners + count, outOfRange), vertexCount);
}

void
polygon_indices_internal::requireValidIndices(const SurfaceMesh& mesh)
{
    const std::string badIndex = firstBadIndex(mesh);
    if (!badIndex.empty()) throw ParameterError(badIndex);
}

namespace {

/// measureAreaAndVolume(), also counting the polygons of zero area in @a zeroArea.
AreaAndVolume
sumAreaAndVolume(const SurfaceMesh& mesh, size_t& zeroArea)
{
    AreaAndVolume m;
    const size_t vertexCount = mesh.points.size();
    size_t polygon = 0;
    for (const openvdb::Vec3I& t : mesh.triangles) {
        for (int i = 0; i < 3; ++i) {
            if (t[i] >= vertexCount) throwBadIndex(mesh, polygon, t[i]);
        }
        zeroArea += (addTriangle(mesh, t[0], t[1], t[2], m) == 0.0);
        ++polygon;
    }
    for (const openvdb::Vec4I& q : mesh.quads) {
        for (int i = 0; i < 4; ++i) {
            if (q[i] >= vertexCount) throwBadIndex(mesh, polygon, q[i]);
        }
        const double first = addTriangle(mesh, q[0], q[1], q[2], m);
        const double second = addTriangle(mesh, q[0], q[2], q[3], m);
        zeroArea += (first + second) == 0.0;
        ++polygon;
    }
    return m;
}

} // namespace

AreaAndVolume
measureAreaAndVolume(const SurfaceMesh& mesh)
{
    size_t zeroArea = 0;
    return sumAreaAndVolume(mesh, zeroArea);
}

MeshMeasures
measureMesh(const SurfaceMesh& mesh)
{
    MeshMeasures m;
    m.vertices = mesh.points.size();
    m.polygons = mesh.polygonCount();
    // Checks every index first (the same error for the same mesh), so the loop below may trust them.
    const AreaAndVolume sums = sumAreaAndVolume(mesh, m.zeroAreaPolygons);
    m.area = sums.area;
    m.volume = sums.volume;
    for (const openvdb::Vec3s& p : mesh.points) {
        m.nonFiniteVertices += !(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]));
    }

    std::vector<bool> used(mesh.points.size(), false);
    std::vector<EdgeUse> edges;
    edges.reserve(3 * mesh.triangles.size() + 4 * mesh.quads.size());
    for (const openvdb::Vec3I& t : mesh.triangles) {
        for (int i = 0; i < 3; ++i) used[t[i]] = true;
        for (int i = 0; i < 3; ++i) addEdge(edges, t[i], t[(i + 1) % 3]);
    }
    for (const openvdb::Vec4I& q : mesh.quads) {
        for (int i = 0; i < 4; ++i) used[q[i]] = true;
        for (int i = 0; i < 4; ++i) addEdge(edges, q[i], q[(i + 1) % 4]);
    }
    m.unusedVertices = size_t(std::count(used.begin(), used.end(), false));

    std::sort(edges.begin(), edges.end());
    for (size_t begin = 0; begin < edges.size();) {
        size_t end = begin;
        size_t forward = 0;
        while (end < edges.size() && edges[end].key == edges[begin].key) {
            forward += edges[end].forward ? 1 : 0;
            ++end;
        }
        const size_t uses = end - begin;
        const size_t backward = uses - forward;
        if (uses == 1) ++m.boundaryEdges;
        else if (uses >= 3) ++m.nonManifoldEdges;
        else if (forward == 2 || backward == 2) ++m.inconsistentEdges;
        begin = end;
    }

    m.closed = m.polygons > 0 && m.boundaryEdges == 0;
    m.manifold = m.closed && m.nonManifoldEdges == 0 && m.inconsistentEdges == 0;
    return m;
}

} // namespace nonbloppy
