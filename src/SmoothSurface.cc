// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/SmoothSurface.h>

#include <nonbloppy/Error.h>

#include "Cancellation.h"
#include "PolygonIndices.h"
#include "SurfaceStages.h"
#include "VectorArea.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <vector>

namespace nonbloppy {

namespace {

using cancellation_internal::CancelPoll;
using openvdb::Vec3d;
using openvdb::Vec3I;
using openvdb::Vec3s;

/// One polygon's corners: three for a triangle, four for a quad.
struct Corners
{
    uint32_t vertex[4];
    int count;
};

/// The mesh's polygons, triangles first, then quads.
struct Polygons
{
    const SurfaceMesh& mesh;
    size_t size() const { return mesh.triangles.size() + mesh.quads.size(); }
    Corners operator[](size_t n) const
    {
        if (n < mesh.triangles.size()) {
            const Vec3I& t = mesh.triangles[n];
            return Corners{{t[0], t[1], t[2], 0}, 3};
        }
        const openvdb::Vec4I& q = mesh.quads[n - mesh.triangles.size()];
        return Corners{{q[0], q[1], q[2], q[3]}, 4};
    }
};

/// Polygons around each vertex, in ascending order: vertex v's are
/// polygonOf[start[v] .. start[v + 1]).
struct VertexPolygons
{
    std::vector<uint64_t> start;
    std::vector<uint32_t> polygonOf;
};

VertexPolygons vertexPolygons(const Polygons& polygons, size_t vertexCount, CancelPoll& poll)
{
    VertexPolygons out;
    out.start.assign(vertexCount + 1, 0);
    for (size_t n = 0; n < polygons.size(); ++n) {
        if (poll.stoppedAt(n)) poll.throwIfStopped();
        const Corners t = polygons[n];
        for (int k = 0; k < t.count; ++k) ++out.start[t.vertex[k] + 1];
    }
    for (size_t v = 0; v < vertexCount; ++v) out.start[v + 1] += out.start[v];
    out.polygonOf.resize(out.start.back());
    std::vector<uint64_t> fill(out.start.begin(), out.start.end() - 1);
    for (size_t n = 0; n < polygons.size(); ++n) {
        if (poll.stoppedAt(n)) poll.throwIfStopped();
        const Corners t = polygons[n];
        for (int k = 0; k < t.count; ++k) out.polygonOf[fill[t.vertex[k]]++] = uint32_t(n);
    }
    return out;
}

/// For each polygon i, every polygon j sharing a vertex with it (i itself included), once,
/// in ascending order, with the part of the normal filter's weight that stays the same from
/// round to round: area_j · (number of vertices shared) · exp(−|c_i − c_j|²/2σ_c²).
/// Polygon i's are polygon[start[i] .. start[i + 1]).
struct PolygonNeighbours
{
    std::vector<uint64_t> start;
    std::vector<uint32_t> polygon;
    std::vector<float> weight;
};

PolygonNeighbours polygonNeighbours(const Polygons& polygons, const VertexPolygons& around,
                                    const std::vector<Vec3s>& centroid, const std::vector<float>& area,
                                    float spatialScale, CancelPoll& poll)
{
    const size_t polygonCount = polygons.size();
    // The polygons around i's corners, sorted: a polygon sharing k vertices with i
    // appears k times in a row. Calls @a visit(j, k) for each.
    auto forEachNeighbour = [&](size_t i, std::vector<uint32_t>& scratch, auto&& visit) {
        scratch.clear();
        const Corners t = polygons[i];
        for (int k = 0; k < t.count; ++k) {
            scratch.insert(scratch.end(), around.polygonOf.begin() + ptrdiff_t(around.start[t.vertex[k]]),
                           around.polygonOf.begin() + ptrdiff_t(around.start[t.vertex[k] + 1]));
        }
        std::sort(scratch.begin(), scratch.end());
        for (size_t a = 0; a < scratch.size();) {
            size_t b = a + 1;
            while (b < scratch.size() && scratch[b] == scratch[a]) ++b;
            visit(scratch[a], float(b - a));
            a = b;
        }
    };
    PolygonNeighbours out;
    out.start.assign(polygonCount + 1, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, polygonCount),
        [&](const tbb::blocked_range<size_t>& range) {
            std::vector<uint32_t> scratch;
            for (size_t i = range.begin(); i < range.end(); ++i) {
                if (poll.stoppedAt(i - range.begin())) return;
                uint64_t count = 0;
                forEachNeighbour(i, scratch, [&](uint32_t, float) { ++count; });
                out.start[i + 1] = count;
            }
        });
    poll.throwIfStopped();
    for (size_t i = 0; i < polygonCount; ++i) out.start[i + 1] += out.start[i];
    out.polygon.resize(out.start.back());
    out.weight.resize(out.start.back());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, polygonCount),
        [&](const tbb::blocked_range<size_t>& range) {
            std::vector<uint32_t> scratch;
            for (size_t i = range.begin(); i < range.end(); ++i) {
                if (poll.stoppedAt(i - range.begin())) return;
                uint64_t e = out.start[i];
                forEachNeighbour(i, scratch, [&](uint32_t j, float shared) {
                    out.polygon[e] = j;
                    out.weight[e] = area[j] * shared * std::exp(-spatialScale * (centroid[j] - centroid[i]).lengthSqr());
                    ++e;
                });
            }
        });
    poll.throwIfStopped();
    return out;
}

/// Centroid of every polygon, and (when asked) its area and unit normal.
void measurePolygons(const Polygons& polygons, const std::vector<Vec3s>& points,
                     std::vector<Vec3s>& centroid, std::vector<float>* area, std::vector<Vec3s>* normal,
                     CancelPoll& poll)
{
    tbb::parallel_for(tbb::blocked_range<size_t>(0, polygons.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t n = range.begin(); n < range.end(); ++n) {
                if (poll.stoppedAt(n - range.begin())) return;
                const Corners t = polygons[n];
                const Vec3s a = points[t.vertex[0]], b = points[t.vertex[1]], c = points[t.vertex[2]];
                const Vec3s d = t.count == 4 ? points[t.vertex[3]] : Vec3s(0.0f);
                centroid[n] = t.count == 4 ? (a + b + c + d) * 0.25f : (a + b + c) * (1.0f / 3.0f);
                if (!area) continue;
                const Vec3s cross = t.count == 4 ? twiceVectorArea(a, b, c, d) : twiceVectorArea(a, b, c);
                const float length = cross.length();
                (*area)[n] = 0.5f * length;
                (*normal)[n] = length > 0.0f ? cross / length : Vec3s(0.0f);
            }
        });
    poll.throwIfStopped();
}

} // namespace

void smoothSurface(SurfaceMesh& mesh, const SmoothSettings& settings, openvdb::util::NullInterrupter* interrupter)
{
    polygon_indices_internal::requireValidIndices(mesh);
    surface_stages_internal::smoothSurfaceUnchecked(mesh, settings, interrupter);
}

void surface_stages_internal::smoothSurfaceUnchecked(SurfaceMesh& mesh, const SmoothSettings& settings,
                                                     openvdb::util::NullInterrupter* interrupter)
{
    std::ostringstream msg;
    if (!(settings.spatialWidth > 0.0) || !std::isfinite(settings.spatialWidth)) {
        msg << "smoothing width must be > 0, got " << settings.spatialWidth;
        throw ParameterError(msg.str());
    }
    if (!(settings.normalWidth > 0.0) || !std::isfinite(settings.normalWidth)) {
        msg << "smoothing normal width must be > 0, got " << settings.normalWidth;
        throw ParameterError(msg.str());
    }
    if (settings.normalRounds < 0 || settings.vertexRounds < 0) {
        msg << "smoothing rounds must be >= 0, got " << settings.normalRounds << " normal and "
            << settings.vertexRounds << " vertex rounds";
        throw ParameterError(msg.str());
    }
    const Polygons polygons{mesh};
    if (settings.normalRounds == 0 || settings.vertexRounds == 0 || polygons.size() == 0) return;
    if (polygons.size() > UINT32_MAX) throw ParameterError("cannot smooth more than 2^32 polygons");

    CancelPoll poll(interrupter, "smooth surface");
    const size_t polygonCount = polygons.size();
    const VertexPolygons around = vertexPolygons(polygons, mesh.points.size(), poll);

    std::vector<Vec3s> centroid(polygonCount), normal(polygonCount), filtered(polygonCount);
    std::vector<float> area(polygonCount);
    measurePolygons(polygons, mesh.points, centroid, &area, &normal, poll);

    // Normal rounds: every polygon reads the previous round's normals only (double
    // buffered), in a fixed neighbour order, so the result does not depend on the threads.
    // The centroids do not move during these rounds: their part of the weight is computed once.
    const float spatialScale = float(0.5 / (settings.spatialWidth * settings.spatialWidth));
    const float normalScale = float(0.5 / (settings.normalWidth * settings.normalWidth));
    {
        const PolygonNeighbours neighbours =
            polygonNeighbours(polygons, around, centroid, area, spatialScale, poll);
        std::vector<float>().swap(area);
        for (int round = 0; round < settings.normalRounds; ++round) {
            tbb::parallel_for(tbb::blocked_range<size_t>(0, polygonCount),
                [&](const tbb::blocked_range<size_t>& range) {
                    for (size_t n = range.begin(); n < range.end(); ++n) {
                        if (poll.stoppedAt(n - range.begin())) return;
                        const Vec3s own = normal[n];
                        float x = 0.0f, y = 0.0f, z = 0.0f;
                        for (uint64_t e = neighbours.start[n]; e < neighbours.start[n + 1]; ++e) {
                            const Vec3s other = normal[neighbours.polygon[e]];
                            const float dx = other[0] - own[0], dy = other[1] - own[1], dz = other[2] - own[2];
                            const float w = neighbours.weight[e] * std::exp(-normalScale * (dx * dx + dy * dy + dz * dz));
                            x += w * other[0];
                            y += w * other[1];
                            z += w * other[2];
                        }
                        const float length = std::sqrt(x * x + y * y + z * z);
                        filtered[n] = length > 0.0f ? Vec3s(x / length, y / length, z / length) : own;
                    }
                });
            poll.throwIfStopped();
            normal.swap(filtered);
        }
    }

    // Vertex rounds: move each vertex along its polygons' filtered normals onto their planes.
    std::vector<Vec3s> next(mesh.points.size());
    for (int round = 0; round < settings.vertexRounds; ++round) {
        if (round > 0) measurePolygons(polygons, mesh.points, centroid, nullptr, nullptr, poll);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.points.size()),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t v = range.begin(); v < range.end(); ++v) {
                    if (poll.stoppedAt(v - range.begin())) return;
                    const Vec3s p = mesh.points[v];
                    const uint64_t begin = around.start[v], end = around.start[v + 1];
                    if (begin == end) { next[v] = p; continue; }
                    Vec3d move(0.0);
                    for (uint64_t e = begin; e < end; ++e) {
                        const uint32_t m = around.polygonOf[e];
                        move += Vec3d(normal[m]) * double(normal[m].dot(centroid[m] - p));
                    }
                    next[v] = p + Vec3s(move / double(end - begin));
                }
            });
        poll.throwIfStopped();
        mesh.points.swap(next);
    }
}

} // namespace nonbloppy
