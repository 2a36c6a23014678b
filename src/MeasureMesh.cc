// SPDX-License-Identifier: Apache-2.0
/// @file MeasureMesh.cc
/// @brief Edge topology (boundary, non-manifold, inconsistent), area and signed volume.

#include <nonbloppy/MeasureMesh.h>

#include <nonbloppy/Error.h>

#include "PolygonIndices.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <functional>
#include <memory>
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
};

/// The key of no edge: a polygon's collapsed edge (both ends one vertex) bounds nothing.
constexpr uint64_t kNoEdge = ~uint64_t(0);

EdgeUse
edgeOf(uint32_t from, uint32_t to)
{
    if (from == to) return {kNoEdge, false};
    const uint32_t low = std::min(from, to), high = std::max(from, to);
    return {(uint64_t(low) << 32) | high, from < to};
}

/// Edges by how many polygons use them, in a part of the sorted edge list.
struct EdgeCounts
{
    size_t boundary = 0, nonManifold = 0, inconsistent = 0;
};

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
    const size_t vertexCount = mesh.points.size();
    const size_t triangleCount = mesh.triangles.size(), polygonCount = m.polygons;
    m.nonFiniteVertices = tbb::parallel_reduce(tbb::blocked_range<size_t>(0, vertexCount), size_t(0),
        [&](const tbb::blocked_range<size_t>& range, size_t count) {
            for (size_t i = range.begin(); i < range.end(); ++i) {
                const openvdb::Vec3s& p = mesh.points[i];
                count += !(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]));
            }
            return count;
        },
        std::plus<size_t>());

    // Every polygon's edges at a fixed place (a triangle's three, then a quad's four, in
    // polygon order), collapsed ones as kNoEdge, which sorts last; then sorted in parallel.
    // Only counts come out of the sorted runs, so the order within a run does not matter.
    const auto firstEdge = [&](size_t polygon) {
        return polygon < triangleCount ? 3 * polygon : 3 * triangleCount + 4 * (polygon - triangleCount);
    };
    std::unique_ptr<std::atomic<uint8_t>[]> used(new std::atomic<uint8_t>[vertexCount]());
    std::vector<EdgeUse> edges(firstEdge(polygonCount));
    tbb::parallel_for(tbb::blocked_range<size_t>(0, polygonCount), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t n = range.begin(); n < range.end(); ++n) {
            const uint32_t* corners = n < triangleCount ? mesh.triangles[n].asPointer()
                                                        : mesh.quads[n - triangleCount].asPointer();
            const int count = n < triangleCount ? 3 : 4;
            EdgeUse* out = edges.data() + firstEdge(n);
            for (int i = 0; i < count; ++i) {
                used[corners[i]].store(1, std::memory_order_relaxed);
                out[i] = edgeOf(corners[i], corners[(i + 1) % count]);
            }
        }
    });
    size_t usedCount = 0;
    for (size_t i = 0; i < vertexCount; ++i) usedCount += used[i].load(std::memory_order_relaxed);
    m.unusedVertices = vertexCount - usedCount;
    tbb::parallel_sort(edges.begin(), edges.end(),
                       [](const EdgeUse& a, const EdgeUse& b) { return a.key < b.key; });
    edges.erase(std::lower_bound(edges.begin(), edges.end(), EdgeUse{kNoEdge, false},
                                 [](const EdgeUse& a, const EdgeUse& b) { return a.key < b.key; }),
                edges.end());

    // The runs of equal keys, counted in chunks that each start at a run's first element.
    constexpr size_t kChunk = size_t(1) << 16;
    const size_t chunks = (edges.size() + kChunk - 1) / kChunk;
    std::vector<EdgeCounts> counted(chunks);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t c = range.begin(); c < range.end(); ++c) {
            // A run belongs to the chunk holding its first element.
            size_t begin = c * kChunk;
            const size_t chunkEnd = std::min(begin + kChunk, edges.size());
            while (begin > 0 && begin < chunkEnd && edges[begin].key == edges[begin - 1].key) ++begin;
            EdgeCounts& counts = counted[c];
            while (begin < chunkEnd) {
                size_t end = begin;
                size_t forward = 0;
                while (end < edges.size() && edges[end].key == edges[begin].key) {
                    forward += edges[end].forward ? 1 : 0;
                    ++end;
                }
                const size_t uses = end - begin;
                const size_t backward = uses - forward;
                if (uses == 1) ++counts.boundary;
                else if (uses >= 3) ++counts.nonManifold;
                else if (forward == 2 || backward == 2) ++counts.inconsistent;
                begin = end;
            }
        }
    });
    for (const EdgeCounts& counts : counted) {
        m.boundaryEdges += counts.boundary;
        m.nonManifoldEdges += counts.nonManifold;
        m.inconsistentEdges += counts.inconsistent;
    }

    m.closed = m.polygons > 0 && m.boundaryEdges == 0;
    m.manifold = m.closed && m.nonManifoldEdges == 0 && m.inconsistentEdges == 0;
    return m;
}

} // namespace nonbloppy
