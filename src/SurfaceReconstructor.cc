// SPDX-License-Identifier: Apache-2.0
/// @file SurfaceReconstructor.cc
/// @brief The buildSurface() pipeline with buffers kept between frames.
///
/// The stages after "index particles" are buildSurface()'s own (src/SurfaceStages.cc);
/// test_SurfaceReconstructor.cc checks that both give the same bytes.

#include <nonbloppy/SurfaceReconstructor.h>

#include "ParticleIndexImpl.h"
#include "SurfaceStages.h"

namespace nonbloppy {

using surface_stages_internal::checkCancelled;
using surface_stages_internal::givenRadius;
using surface_stages_internal::kCellOverRadius;
using surface_stages_internal::StageScope;

SurfaceReconstructor::SurfaceReconstructor(const SurfaceParameters& params) : mParams(params) {}

SurfaceReconstructor::~SurfaceReconstructor() = default;

void
SurfaceReconstructor::setParameters(const SurfaceParameters& params)
{
    mParams = params;
    mHaveKeptParameters = false;
}

std::vector<openvdb::Vec3f>&
SurfaceReconstructor::positionBuffer(size_t count)
{
    if (mPositions.capacity() < count) {
        // The previous frame's sorted positions are no longer needed once a new frame
        // starts: take their storage instead of allocating. The index owns its Impl
        // (non-const), so casting away the accessor's const is well defined.
        auto& sorted = const_cast<ParticleIndex::Impl&>(mIndex.impl()).sortedPositions;
        if (sorted.capacity() > mPositions.capacity()) mPositions.swap(sorted);
    }
    mPositions.resize(count);
    return mPositions;
}

const SurfaceResult&
SurfaceReconstructor::reconstructBuffered(openvdb::util::NullInterrupter* interrupter)
{
    SurfaceResult& result = mResult;
    result.timings = StageTimings();
    result.density.reset();
    result.particleCount = mPositions.size();
    const auto indexParticles = [&](double effectiveRadius) {
        StageScope scope(result.timings, interrupter, "index particles");
        // build() takes the vector over; positionBuffer() takes storage back next frame.
        mIndex = ParticleIndex::build(std::move(mPositions), kCellOverRadius * effectiveRadius, interrupter);
        mPositions = std::vector<openvdb::Vec3f>();
        checkCancelled(interrupter, "index particles");
    };
    const bool reuse = mKeepParameters && mHaveKeptParameters;
    // As buildSurface(): with r_e given the index comes first and serves the spacing estimate.
    const bool indexFirst = !reuse && givenRadius(mParams);
    if (indexFirst) indexParticles(*mParams.effectiveRadius);
    {
        StageScope scope(result.timings, interrupter, "estimate parameters");
        if (reuse) {
            result.parameters = mKeptParameters;
        } else {
            result.parameters = indexFirst ? resolveParametersIndexed(mParams, mIndex, interrupter)
                                           : resolveParameters(mParams, mPositions, interrupter);
            mKeptParameters = result.parameters;
            mHaveKeptParameters = true;
        }
        checkCancelled(interrupter, "estimate parameters");
    }
    if (!indexFirst) indexParticles(result.parameters.effectiveRadius);
    surface_stages_internal::runSurfaceStages(mIndex, mParams.keepDensity, result, mUnrelaxed,
                                              surface_stages_internal::UnrelaxedBuffer::Keep,
                                              interrupter);
    ++mFrames;
    return result;
}

} // namespace nonbloppy
