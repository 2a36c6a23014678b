// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/ParticleIndex.h>

#include "SurfaceStages.h"

namespace nonbloppy {

using surface_stages_internal::checkCancelled;
using surface_stages_internal::givenRadius;
using surface_stages_internal::kCellOverRadius;
using surface_stages_internal::StageScope;

SurfaceResult buildSurface(std::vector<openvdb::Vec3f> positions, const SurfaceParameters& params,
                           openvdb::util::NullInterrupter* interrupter)
{
    SurfaceResult result;
    result.particleCount = positions.size();
    ParticleIndex index;
    const auto indexParticles = [&](double effectiveRadius) {
        StageScope scope(result.timings, interrupter, "index particles");
        index = ParticleIndex::build(std::move(positions), kCellOverRadius * effectiveRadius, interrupter);
        checkCancelled(interrupter, "index particles");
    };
    // With r_e given, the index the stages use can be built first and serve the spacing
    // estimate too; otherwise r_e (hence the index's cells) waits for the estimate.
    const bool indexFirst = givenRadius(params);
    if (indexFirst) indexParticles(*params.effectiveRadius);
    {
        StageScope scope(result.timings, interrupter, "estimate parameters");
        result.parameters = indexFirst ? resolveParametersIndexed(params, index, interrupter)
                                       : resolveParameters(params, positions, interrupter);
        checkCancelled(interrupter, "estimate parameters");
    }
    if (!indexFirst) indexParticles(result.parameters.effectiveRadius);
    std::vector<openvdb::Vec3s> unrelaxed;  // freed after fold repair, before the normals
    surface_stages_internal::runSurfaceStages(index, params.keepDensity, result, unrelaxed,
                                              surface_stages_internal::UnrelaxedBuffer::Release,
                                              interrupter);
    return result;
}

} // namespace nonbloppy
