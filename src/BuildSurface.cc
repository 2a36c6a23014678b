// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/ParticleIndex.h>

#include "SurfaceStages.h"
#include "UnwrittenVector.h"

namespace nonbloppy {

SurfaceResult buildSurface(std::vector<openvdb::Vec3f> positions, const SurfaceParameters& params,
                           openvdb::util::NullInterrupter* interrupter)
{
    SurfaceResult result;
    result.particleCount = positions.size();
    ParticleIndex index;
    surface_stages_internal::resolveAndIndex(params, nullptr, positions, index, result, interrupter);
    // Freed after fold repair, before the normals; filled in parallel, without a memset.
    memory_internal::UnwrittenVector<openvdb::Vec3s> unrelaxed;
    surface_stages_internal::runSurfaceStages(index, params, result, unrelaxed,
                                              surface_stages_internal::UnrelaxedBuffer::Release,
                                              interrupter);
    return result;
}

} // namespace nonbloppy
