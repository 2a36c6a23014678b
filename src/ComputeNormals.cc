// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/ComputeNormals.h>

#include "Cancellation.h"
#include "VectorArea.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <memory>

namespace nonbloppy {

namespace {

/// Fewest vertices worth a range of their own in the normal sums (a range walks every
/// polygon, so small meshes stay in one).
constexpr size_t kMinVerticesPerRange = 65536;

} // namespace

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
    // Each task takes one range of vertex numbers and walks every polygon in order, adding
    // the normals of the corners in its range: every vertex still sums its polygons in
    // polygon order, so the result has the same bits for any number of ranges. Extraction
    // numbers vertices and polygons region by region, so most polygons have all their
    // corners in one range and their normal is computed by one task only.
    const size_t vertexCount = p.size();
    const size_t ranges = std::clamp<size_t>(size_t(tbb::this_task_arena::max_concurrency()), 1,
                                             vertexCount / kMinVerticesPerRange + 1);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, ranges, 1), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t k = range.begin(); k < range.end(); ++k) {
            const uint32_t first = uint32_t(k * vertexCount / ranges);
            const uint32_t count = uint32_t((k + 1) * vertexCount / ranges) - first;
            const auto mine = [&](uint32_t v) { return v - first < count; };  // first <= v < first + count
            for (size_t n = 0; n < mesh.triangles.size(); ++n) {
                if (poll.stoppedAt(n)) return;
                const openvdb::Vec3I& t = mesh.triangles[n];
                if (!(mine(t[0]) || mine(t[1]) || mine(t[2]))) continue;
                const openvdb::Vec3d normal = twiceVectorArea(openvdb::Vec3d(p[t[0]]), openvdb::Vec3d(p[t[1]]),
                                                              openvdb::Vec3d(p[t[2]]));
                for (int c = 0; c < 3; ++c) {
                    if (mine(t[c])) sums[t[c]] += normal;
                }
            }
            for (size_t n = 0; n < mesh.quads.size(); ++n) {
                if (poll.stoppedAt(n)) return;
                const openvdb::Vec4I& q = mesh.quads[n];
                if (!(mine(q[0]) || mine(q[1]) || mine(q[2]) || mine(q[3]))) continue;
                const openvdb::Vec3d normal = twiceVectorArea(openvdb::Vec3d(p[q[0]]), openvdb::Vec3d(p[q[1]]),
                                                              openvdb::Vec3d(p[q[2]]), openvdb::Vec3d(p[q[3]]));
                for (int c = 0; c < 4; ++c) {
                    if (mine(q[c])) sums[q[c]] += normal;
                }
            }
        }
    });
    poll.throwIfStopped();
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
