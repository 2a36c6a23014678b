// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/ParticleIndex.h>

#include "SurfaceStages.h"

namespace nonbloppy {

using surface_stages_internal::checkCancelled;
using surface_stages_internal::kCellOverRadius;
using surface_stages_internal::StageScope;

SurfaceResult buildSurface(std::vector<openvdb::Vec3f> positions, const SurfaceParameters& params,
                           openvdb::util::NullInterrupter* interrupter)
{
    SurfaceResult result;
    result.particleCount = positions.size();
    {
        StageScope scope(result.timings, interrupter, "estimate parameters");
        result.parameters = resolveParameters(params, positions, interrupter);
        checkCancelled(interrupter, "estimate parameters");
    }
    const ResolvedParameters& p = result.parameters;

    ParticleIndex index;
    {
        StageScope scope(result.timings, interrupter, "index particles");
        index = ParticleIndex::build(std::move(positions), kCellOverRadius * p.effectiveRadius,
                                     interrupter);
        checkCancelled(interrupter, "index particles");
    }
    std::vector<openvdb::Vec3s> unrelaxed;  // freed after fold repair, before the normals
    surface_stages_internal::runSurfaceStages(index, params.keepDensity, result, unrelaxed,
                                              surface_stages_internal::UnrelaxedBuffer::Release,
                                              interrupter);
    return result;
}

} // namespace nonbloppy
