// SPDX-License-Identifier: Apache-2.0
/// @file MeasureMesh.cc
/// @brief Edge topology (boundary, non-manifold, inconsistent), area and signed volume.

#include <nonbloppy/MeasureMesh.h>

#include <nonbloppy/Error.h>

#include "PolygonIndices.h"
#include "VectorArea.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace nonbloppy {

namespace {

/// Edges by how many polygons use them.
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
    const double area = 0.5 * twiceVectorArea(p0, p1, p2).length();
    m.area += area;
    m.volume += sixTimesSignedVolume(p0, p1, p2) / 6.0;
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
    const size_t polygonCount = mesh.triangles.size() + mesh.quads.size();
    const auto outOfRange = [&](uint32_t index) { return index >= vertexCount; };
    const size_t bad = tbb::parallel_reduce(tbb::blocked_range<size_t>(0, polygonCount), polygonCount,
        [&](const tbb::blocked_range<size_t>& range, size_t found) {
            for (size_t n = range.begin(); n < range.end() && n < found; ++n) {
                const auto [corners, count] = cornersOf(mesh, n);
                if (std::any_of(corners, corners + count, outOfRange)) return n;
            }
            return found;
        },
        [](size_t a, size_t b) { return std::min(a, b); });
    if (bad == polygonCount) return std::string();
    const auto [corners, count] = cornersOf(mesh, bad);
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
    const size_t polygonCount = m.polygons;
    m.nonFiniteVertices = tbb::parallel_reduce(tbb::blocked_range<size_t>(0, vertexCount), size_t(0),
        [&](const tbb::blocked_range<size_t>& range, size_t count) {
            for (size_t i = range.begin(); i < range.end(); ++i) {
                const openvdb::Vec3s& p = mesh.points[i];
                count += !(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]));
            }
            return count;
        },
        std::plus<size_t>());

    // Each edge is filed under its lower vertex (a counting sort: the edges per vertex, their
    // prefix sums, then every edge put in one of its vertex's slots), as its other end and
    // direction; then each vertex's few edges are sorted and their runs counted. Only counts
    // come out, so the order in which the threads file the edges does not matter.
    const auto forEachEdge = [&](size_t polygon, auto&& visit) {
        const auto [corners, count] = polygon_indices_internal::cornersOf(mesh, polygon);
        for (int i = 0; i < count; ++i) {
            const uint32_t from = corners[i], to = corners[(i + 1) % count];
            if (from != to) visit(from, to);  // a collapsed edge bounds nothing
        }
    };
    std::unique_ptr<std::atomic<uint8_t>[]> used(new std::atomic<uint8_t>[vertexCount]());
    std::unique_ptr<std::atomic<uint32_t>[]> filed(new std::atomic<uint32_t>[vertexCount]());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, polygonCount), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t n = range.begin(); n < range.end(); ++n) {
            // Every corner is used, those of a polygon collapsed to one point too.
            const auto [corners, count] = polygon_indices_internal::cornersOf(mesh, n);
            for (int i = 0; i < count; ++i) used[corners[i]].store(1, std::memory_order_relaxed);
            forEachEdge(n, [&](uint32_t from, uint32_t to) {
                filed[std::min(from, to)].fetch_add(1, std::memory_order_relaxed);
            });
        }
    });
    std::vector<uint64_t> start(vertexCount + 1, 0);
    size_t usedCount = 0;
    for (size_t v = 0; v < vertexCount; ++v) {
        usedCount += used[v].load(std::memory_order_relaxed);
        start[v + 1] = start[v] + filed[v].load(std::memory_order_relaxed);
        filed[v].store(0, std::memory_order_relaxed);
    }
    m.unusedVertices = vertexCount - usedCount;
    // A vertex's edges: (other end << 1) | (used from the lower vertex to the other).
    std::vector<uint64_t> edges(start[vertexCount]);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, polygonCount), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t n = range.begin(); n < range.end(); ++n) {
            forEachEdge(n, [&](uint32_t from, uint32_t to) {
                const uint32_t low = std::min(from, to), high = std::max(from, to);
                edges[start[low] + filed[low].fetch_add(1, std::memory_order_relaxed)] =
                    (uint64_t(high) << 1) | uint64_t(from < to);
            });
        }
    });
    const EdgeCounts counted = tbb::parallel_reduce(tbb::blocked_range<size_t>(0, vertexCount), EdgeCounts(),
        [&](const tbb::blocked_range<size_t>& range, EdgeCounts counts) {
            for (size_t v = range.begin(); v < range.end(); ++v) {
                const auto first = edges.begin() + ptrdiff_t(start[v]), last = edges.begin() + ptrdiff_t(start[v + 1]);
                std::sort(first, last);
                for (auto run = first; run != last;) {
                    auto end = run;
                    size_t forward = 0;
                    while (end != last && (*end >> 1) == (*run >> 1)) forward += size_t(*end++ & 1);
                    const size_t uses = size_t(end - run), backward = uses - forward;
                    if (uses == 1) ++counts.boundary;
                    else if (uses >= 3) ++counts.nonManifold;
                    else if (forward == 2 || backward == 2) ++counts.inconsistent;
                    run = end;
                }
            }
            return counts;
        },
        [](EdgeCounts a, const EdgeCounts& b) {
            a.boundary += b.boundary;
            a.nonManifold += b.nonManifold;
            a.inconsistent += b.inconsistent;
            return a;
        });
    m.boundaryEdges = counted.boundary;
    m.nonManifoldEdges = counted.nonManifold;
    m.inconsistentEdges = counted.inconsistent;

    m.closed = m.polygons > 0 && m.boundaryEdges == 0;
    m.manifold = m.closed && m.nonManifoldEdges == 0 && m.inconsistentEdges == 0;
    return m;
}

} // namespace nonbloppy
