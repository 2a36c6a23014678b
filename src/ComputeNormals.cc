// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/ComputeNormals.h>
#include <nonbloppy/Error.h>

#include "Cancellation.h"
#include "PolygonIndices.h"
#include "VectorArea.h"

#include <tbb/parallel_for.h>

#include <memory>

namespace nonbloppy {

namespace cancellation_internal {

void computeNormals(SurfaceMesh& mesh, CancelPoll& poll)
{
    const std::vector<openvdb::Vec3s>& p = mesh.points;
    // Accumulate in double and in polygon order, so the result is deterministic; each polygon
    // adds its area-weighted normal (twice its vector area).
    // Zeroed in parallel tasks that poll, not by a vector's serial fill: 24 bytes per vertex
    // (~110 MB for 4.5M vertices) take tens of milliseconds to fault in.
    std::unique_ptr<openvdb::Vec3d[]> sums(new openvdb::Vec3d[p.size()]);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, p.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t i = range.begin(); i < range.end(); ++i) {
                if (poll.stoppedAt(i - range.begin())) return;
                sums[i] = openvdb::Vec3d(0.0);
            }
        });
    poll.throwIfStopped();
    // Corners are checked as they are read, in the order firstBadIndex() numbers polygons:
    // free in this serial pass, and mesh.normals is only written once all have passed.
    const size_t vertexCount = p.size(), triangleCount = mesh.triangles.size();
    const auto requireCorner = [&](size_t polygon, uint32_t corner) {
        if (corner >= vertexCount) {
            throw ParameterError(polygon_indices_internal::badIndexMessage(polygon, corner, vertexCount));
        }
    };
    for (size_t n = 0; n < triangleCount; ++n) {
        if (poll.stoppedAt(n)) poll.throwIfStopped();
        const openvdb::Vec3I& t = mesh.triangles[n];
        for (int k = 0; k < 3; ++k) requireCorner(n, t[k]);
        const openvdb::Vec3d a(p[t[0]]), b(p[t[1]]), c(p[t[2]]);
        const openvdb::Vec3d normal = twiceVectorArea(a, b, c);
        sums[t[0]] += normal; sums[t[1]] += normal; sums[t[2]] += normal;
    }
    for (size_t n = 0; n < mesh.quads.size(); ++n) {
        if (poll.stoppedAt(n)) poll.throwIfStopped();
        const openvdb::Vec4I& q = mesh.quads[n];
        for (int k = 0; k < 4; ++k) requireCorner(triangleCount + n, q[k]);
        const openvdb::Vec3d a(p[q[0]]), b(p[q[1]]), c(p[q[2]]), d(p[q[3]]);
        const openvdb::Vec3d normal = twiceVectorArea(a, b, c, d);
        sums[q[0]] += normal; sums[q[1]] += normal; sums[q[2]] += normal; sums[q[3]] += normal;
    }
    mesh.normals.resize(p.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, p.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t i = range.begin(); i < range.end(); ++i) {
                if (poll.stoppedAt(i - range.begin())) return;
                const double length = sums[i].length();
                mesh.normals[i] = length > 0.0 ? openvdb::Vec3s(sums[i] / length) : openvdb::Vec3s(0.0f);
            }
        });
    poll.throwIfStopped();
}

} // namespace cancellation_internal

void computeNormals(SurfaceMesh& mesh, openvdb::util::NullInterrupter* interrupter)
{
    cancellation_internal::CancelPoll poll(interrupter, "compute normals");
    cancellation_internal::computeNormals(mesh, poll);
}

} // namespace nonbloppy
