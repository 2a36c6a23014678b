// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/ComputeNormals.h>

#include <tbb/parallel_for.h>

namespace nonbloppy {

void computeNormals(SurfaceMesh& mesh)
{
    const std::vector<openvdb::Vec3s>& p = mesh.points;
    // Accumulate in double and in polygon order, so the result is deterministic; twice the
    // area-weighted normal is the cross product of a triangle's edges, or of a quad's diagonals.
    std::vector<openvdb::Vec3d> sums(p.size(), openvdb::Vec3d(0.0));
    for (const openvdb::Vec3I& t : mesh.triangles) {
        const openvdb::Vec3d a(p[t[0]]), b(p[t[1]]), c(p[t[2]]);
        const openvdb::Vec3d n = (b - a).cross(c - a);
        sums[t[0]] += n; sums[t[1]] += n; sums[t[2]] += n;
    }
    for (const openvdb::Vec4I& q : mesh.quads) {
        const openvdb::Vec3d a(p[q[0]]), b(p[q[1]]), c(p[q[2]]), d(p[q[3]]);
        const openvdb::Vec3d n = (c - a).cross(d - b);
        sums[q[0]] += n; sums[q[1]] += n; sums[q[2]] += n; sums[q[3]] += n;
    }
    mesh.normals.resize(p.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, p.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t i = range.begin(); i < range.end(); ++i) {
                const double length = sums[i].length();
                mesh.normals[i] = length > 0.0 ? openvdb::Vec3s(sums[i] / length) : openvdb::Vec3s(0.0f);
            }
        });
}

} // namespace nonbloppy
