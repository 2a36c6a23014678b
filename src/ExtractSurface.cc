// SPDX-License-Identifier: Apache-2.0
// The only translation unit that includes tools/VolumeToMesh.h (heavy to compile).
#include <nonbloppy/Error.h>
#include <nonbloppy/ExtractSurface.h>

#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <sstream>

namespace nonbloppy {

namespace {

template<typename GridT>
SurfaceMesh extract(const GridT& density, double threshold, double adaptivity)
{
    if (!std::isfinite(threshold)) {
        std::ostringstream msg;
        msg << "--threshold must be finite, got " << threshold;
        throw ParameterError(msg.str());
    }
    if (!(adaptivity >= 0.0 && adaptivity <= 1.0)) {
        std::ostringstream msg;
        msg << "--adaptivity must lie in [0,1], got " << adaptivity;
        throw ParameterError(msg.str());
    }
    SurfaceMesh mesh;
    openvdb::tools::volumeToMesh(density, mesh.points, mesh.triangles, mesh.quads, threshold, adaptivity);
    // The density grows inwards, the opposite of a level set, so volumeToMesh's polygons run
    // clockwise seen from outside: reverse each one.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.quads.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t n = range.begin(); n < range.end(); ++n) {
                const openvdb::Vec4I q = mesh.quads[n];
                mesh.quads[n] = openvdb::Vec4I(q[3], q[2], q[1], q[0]);
            }
        });
    for (openvdb::Vec3I& t : mesh.triangles) std::swap(t[0], t[2]);
    return mesh;
}

} // namespace

SurfaceMesh extractSurface(const openvdb::FloatGrid& density, double threshold, double adaptivity)
{
    return extract(density, threshold, adaptivity);
}

SurfaceMesh extractSurface(const openvdb::DoubleGrid& density, double threshold, double adaptivity)
{
    return extract(density, threshold, adaptivity);
}

} // namespace nonbloppy
