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
    // The old index is now without its positions (or about to be replaced): empty it, so
    // that particleIndex() is a valid, empty index if this frame throws before indexing.
    // Before, a failed frame left the old grid pointing past the swapped-out array, and
    // relaxVertices() against particleIndex() read out of bounds.
    mIndex = ParticleIndex();
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
    // Parameters kept from an earlier frame, or resolved for this one and kept from then on,
    // once the frame is done: a frame that throws or is stopped after resolving them must
    // leave the next frame as a fresh object would (the header's promise).
    const bool reuse = mKeepParameters && mHaveKeptParameters;
    try {
        surface_stages_internal::resolveAndIndex(mParams, reuse ? &mKeptParameters : nullptr, mPositions,
                                                 mIndex, result, interrupter);
        surface_stages_internal::runSurfaceStages(mIndex, mParams, result, mUnrelaxed,
                                                  surface_stages_internal::UnrelaxedBuffer::Keep,
                                                  interrupter);
    } catch (...) {
        // A frame that throws leaves no index behind (see particleIndex()): the positions
        // were moved into a half-built or complete index of a frame that has no result.
        mIndex = ParticleIndex();
        throw;
    }
    if (!reuse) {
        mKeptParameters = result.parameters;
        mHaveKeptParameters = true;
    }
    ++mFrames;
    return result;
}

} // namespace nonbloppy
