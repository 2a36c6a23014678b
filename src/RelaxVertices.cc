// SPDX-License-Identifier: Apache-2.0
#include "ParticleIndexImpl.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/Kernel.h>
#include <nonbloppy/RelaxVertices.h>

#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <sstream>

namespace nonbloppy {

namespace {

/// One relaxation step for a block of vertices: reads `previous`, writes `next`.
struct RelaxStepOp
{
    const ParticleIndex& particles;
    const std::vector<openvdb::Vec3s>& previous;
    std::vector<openvdb::Vec3s>& next;
    float effectiveRadius;
    float blend;
    openvdb::util::NullInterrupter* interrupter;
    std::atomic<bool>& cancelled;

    void operator()(const tbb::blocked_range<size_t>& range) const
    {
        if (cancelled) return;
        if (interrupter && interrupter->wasInterrupted()) { cancelled = true; return; }
        const auto& positions = particles.sortedPositions();
        auto accessor = particles.impl().grid->getConstAccessor();
        const float radius2 = effectiveRadius * effectiveRadius;
        const float minDistance2 = (kMinDistanceFraction * effectiveRadius) * (kMinDistanceFraction * effectiveRadius);
        const openvdb::Vec3d reach(effectiveRadius);
        for (size_t i = range.begin(); i < range.end(); ++i) {
            const openvdb::Vec3s v = previous[i];
            // Sum offsets from the vertex rather than absolute positions: the mean is then
            // exact to float precision however far the fluid is from the origin.
            float weightSum = 0.0f, sx = 0.0f, sy = 0.0f, sz = 0.0f;
            particle_index_internal::forEachRunInBox(accessor, particles.cellSize(),
                openvdb::Vec3d(v) - reach, openvdb::Vec3d(v) + reach,
                [&](uint32_t first, uint32_t end) {
                    for (uint32_t k = first; k < end; ++k) {
                        const float dx = positions[k][0] - v[0];
                        const float dy = positions[k][1] - v[1];
                        const float dz = positions[k][2] - v[2];
                        const float d2 = dx * dx + dy * dy + dz * dz;
                        float w = effectiveRadius / std::sqrt(std::max(d2, minDistance2)) - 1.0f;
                        w = d2 < radius2 ? w : 0.0f;
                        weightSum += w;
                        sx += w * dx;
                        sy += w * dy;
                        sz += w * dz;
                    }
                });
            if (weightSum > 0.0f) {
                const float scale = blend / weightSum;
                next[i] = openvdb::Vec3s(v[0] + scale * sx, v[1] + scale * sy, v[2] + scale * sz);
            } else {
                next[i] = v;  // no particle within r_e: stays put
            }
        }
    }
};

} // namespace

void relaxVertices(SurfaceMesh& mesh, const ParticleIndex& particles, const RelaxSettings& settings,
                   openvdb::util::NullInterrupter* interrupter)
{
    std::ostringstream msg;
    if (!(settings.effectiveRadius > 0.0) || !std::isfinite(settings.effectiveRadius)) {
        msg << "--radius must be > 0, got " << settings.effectiveRadius;
        throw ParameterError(msg.str());
    }
    if (!(settings.blend >= 0.0 && settings.blend <= 1.0)) {
        msg << "--blend must lie in [0,1], got " << settings.blend;
        throw ParameterError(msg.str());
    }
    if (settings.iterations < 0) {
        msg << "--iterations must be >= 0, got " << settings.iterations;
        throw ParameterError(msg.str());
    }
    if (settings.iterations == 0 || settings.blend == 0.0 || mesh.points.empty()) return;

    if (interrupter) interrupter->start("relax vertices");
    std::vector<openvdb::Vec3s> next(mesh.points.size());
    std::atomic<bool> cancelled{false};
    for (int iteration = 0; iteration < settings.iterations && !cancelled; ++iteration) {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.points.size(), 256),
            RelaxStepOp{particles, mesh.points, next, float(settings.effectiveRadius), float(settings.blend),
                        interrupter, cancelled});
        mesh.points.swap(next);
        if (interrupter && interrupter->wasInterrupted(100 * (iteration + 1) / settings.iterations)) {
            cancelled = true;
        }
    }
    if (interrupter) interrupter->end();
    if (cancelled) throw CancelledError("interrupted during relax vertices");
}

} // namespace nonbloppy
