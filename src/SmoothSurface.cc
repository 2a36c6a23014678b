// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/SmoothSurface.h>

#include <nonbloppy/Error.h>

#include "Cancellation.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdint>
#include <sstream>
#include <vector>

namespace nonbloppy {

namespace {

using cancellation_internal::CancelPoll;
using openvdb::Vec3d;
using openvdb::Vec3I;
using openvdb::Vec3s;

/// The mesh's polygons as triangles: its triangles, then each quad as (0,1,2) and (0,2,3).
struct Triangles
{
    const SurfaceMesh& mesh;
    size_t size() const { return mesh.triangles.size() + 2 * mesh.quads.size(); }
    Vec3I operator[](size_t n) const
    {
        if (n < mesh.triangles.size()) return mesh.triangles[n];
        const openvdb::Vec4I& q = mesh.quads[(n - mesh.triangles.size()) / 2];
        return (n - mesh.triangles.size()) % 2 == 0 ? Vec3I(q[0], q[1], q[2]) : Vec3I(q[0], q[2], q[3]);
    }
};

/// Triangles around each vertex, in ascending order: vertex v's are
/// triangleOf[start[v] .. start[v + 1]).
struct VertexTriangles
{
    std::vector<uint64_t> start;
    std::vector<uint32_t> triangleOf;
};

VertexTriangles vertexTriangles(const Triangles& triangles, size_t vertexCount, CancelPoll& poll)
{
    VertexTriangles out;
    out.start.assign(vertexCount + 1, 0);
    for (size_t n = 0; n < triangles.size(); ++n) {
        if (poll.stoppedAt(n)) poll.throwIfStopped();
        const Vec3I t = triangles[n];
        for (int k = 0; k < 3; ++k) ++out.start[t[k] + 1];
    }
    for (size_t v = 0; v < vertexCount; ++v) out.start[v + 1] += out.start[v];
    out.triangleOf.resize(out.start.back());
    std::vector<uint64_t> fill(out.start.begin(), out.start.end() - 1);
    for (size_t n = 0; n < triangles.size(); ++n) {
        if (poll.stoppedAt(n)) poll.throwIfStopped();
        const Vec3I t = triangles[n];
        for (int k = 0; k < 3; ++k) out.triangleOf[fill[t[k]]++] = uint32_t(n);
    }
    return out;
}

/// Centroid of every triangle, and (when asked) its area and unit normal.
void measureTriangles(const Triangles& triangles, const std::vector<Vec3s>& points,
                      std::vector<Vec3s>& centroid, std::vector<float>* area, std::vector<Vec3s>* normal,
                      CancelPoll& poll)
{
    tbb::parallel_for(tbb::blocked_range<size_t>(0, triangles.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t n = range.begin(); n < range.end(); ++n) {
                if (poll.stoppedAt(n - range.begin())) return;
                const Vec3I t = triangles[n];
                const Vec3s a = points[t[0]], b = points[t[1]], c = points[t[2]];
                centroid[n] = (a + b + c) * (1.0f / 3.0f);
                if (!area) continue;
                const Vec3s cross = (b - a).cross(c - a);
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
    const Triangles triangles{mesh};
    if (settings.normalRounds == 0 || settings.vertexRounds == 0 || triangles.size() == 0) return;
    if (triangles.size() > UINT32_MAX) throw ParameterError("cannot smooth more than 2^32 triangles");

    CancelPoll poll(interrupter, "smooth surface");
    const size_t triangleCount = triangles.size();
    const VertexTriangles around = vertexTriangles(triangles, mesh.points.size(), poll);

    std::vector<Vec3s> centroid(triangleCount), normal(triangleCount), filtered(triangleCount);
    std::vector<float> area(triangleCount);
    measureTriangles(triangles, mesh.points, centroid, &area, &normal, poll);

    // Normal rounds: every triangle reads the previous round's normals only (double
    // buffered), in a fixed neighbour order, so the result does not depend on the threads.
    const float spatialScale = float(0.5 / (settings.spatialWidth * settings.spatialWidth));
    const float normalScale = float(0.5 / (settings.normalWidth * settings.normalWidth));
    for (int round = 0; round < settings.normalRounds; ++round) {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, triangleCount),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t n = range.begin(); n < range.end(); ++n) {
                    if (poll.stoppedAt(n - range.begin())) return;
                    const Vec3I t = triangles[n];
                    const Vec3s c = centroid[n], own = normal[n];
                    Vec3d sum(0.0);
                    for (int k = 0; k < 3; ++k) {
                        for (uint64_t e = around.start[t[k]]; e < around.start[t[k] + 1]; ++e) {
                            const uint32_t m = around.triangleOf[e];
                            const float exponent = spatialScale * (centroid[m] - c).lengthSqr()
                                                   + normalScale * (normal[m] - own).lengthSqr();
                            sum += Vec3d(normal[m]) * double(area[m] * std::exp(-exponent));
                        }
                    }
                    const double length = sum.length();
                    filtered[n] = length > 0.0 ? Vec3s(sum / length) : own;
                }
            });
        poll.throwIfStopped();
        normal.swap(filtered);
    }

    // Vertex rounds: move each vertex along its triangles' filtered normals onto their planes.
    std::vector<Vec3s> next(mesh.points.size());
    for (int round = 0; round < settings.vertexRounds; ++round) {
        if (round > 0) measureTriangles(triangles, mesh.points, centroid, nullptr, nullptr, poll);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.points.size()),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t v = range.begin(); v < range.end(); ++v) {
                    if (poll.stoppedAt(v - range.begin())) return;
                    const Vec3s p = mesh.points[v];
                    const uint64_t begin = around.start[v], end = around.start[v + 1];
                    if (begin == end) { next[v] = p; continue; }
                    Vec3d move(0.0);
                    for (uint64_t e = begin; e < end; ++e) {
                        const uint32_t m = around.triangleOf[e];
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
