// SPDX-License-Identifier: Apache-2.0
/// @file DiagnoseSurface.cc
/// @brief The conditions of a finished surface worth a warning (DiagnoseSurface.h).

#include <nonbloppy/DiagnoseSurface.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

namespace nonbloppy {

namespace {

/// Vertices in @a count whose @a isBad(vertex) holds, counted in parallel.
template<typename PredicateT>
size_t countVertices(size_t count, const PredicateT& isBad)
{
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, count, 65536), size_t(0),
        [&](const tbb::blocked_range<size_t>& range, size_t found) {
            for (size_t v = range.begin(); v < range.end(); ++v) found += isBad(v) ? 1 : 0;
            return found;
        },
        std::plus<size_t>());
}

} // namespace

SurfaceDiagnostics diagnoseSurface(const SurfaceResult& result)
{
    SurfaceDiagnostics d;
    const ResolvedParameters& p = result.parameters;
    const SurfaceMesh& mesh = result.mesh;
    d.facesEndInside = !p.thresholdReachesSurface;
    d.empty = result.particleCount > 0 && mesh.points.empty();

    // Not BBoxd::empty(), which is true for particles in one plane (min == max on an axis).
    if (result.particleCount > 0) {
        const openvdb::BBoxd& bounds = result.particleBounds;
        for (int k = 0; k < 3; ++k) {
            d.farthestCoordinate = std::max({d.farthestCoordinate, std::abs(bounds.min()[k]), std::abs(bounds.max()[k])});
        }
        const float atFarthest = float(d.farthestCoordinate);  // exact: the bounds are float positions
        d.floatStep = double(std::nextafter(atFarthest, std::numeric_limits<float>::infinity())) - d.farthestCoordinate;
        // A sixteenth of the spacing keeps the quantization below what the eye sees on a
        // surface s/2 from the particles; without a spacing, h stands for s/2, its default.
        d.floatStepLimit = p.spacing > 0.0 ? p.spacing / 16.0 : p.voxelSize > 0.0 ? p.voxelSize / 8.0 : 0.0;
    }

    const openvdb::Vec3s zero(0.0f);
    d.verticesWithoutNormal = countVertices(mesh.normals.size(), [&](size_t v) { return mesh.normals[v] == zero; });

    for (const MeshAttribute& a : mesh.attributes) {
        if (a.integer || a.components < 1) continue;
        const size_t components = size_t(a.components);
        const size_t vertices = countVertices(a.values.size() / components, [&](size_t v) {
            const float* value = a.values.data() + v * components;
            return std::any_of(value, value + components, [](float x) { return !std::isfinite(x); });
        });
        if (vertices > 0) d.nonFiniteAttributes.emplace_back(a.name, vertices);
    }
    return d;
}

} // namespace nonbloppy
