// SPDX-License-Identifier: Apache-2.0
/// @file SurfaceReconstructor.cc
/// @brief The buildSurface() pipeline with buffers kept between frames.
///
/// This repeats buildSurface()'s chain of stages (src/BuildSurface.cc); when that chain
/// changes, change this one too (test_SurfaceReconstructor.cc compares the two).

#include <nonbloppy/SurfaceReconstructor.h>

#include "ParticleIndexImpl.h"

#include <nonbloppy/ComputeNormals.h>
#include <nonbloppy/CorrectSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/ExtractSurface.h>
#include <nonbloppy/RasterizeDensity.h>
#include <nonbloppy/RelaxVertices.h>
#include <nonbloppy/Version.h>

#include <openvdb/tools/VolumeToMesh.h>

#include <cmath>
#include <sstream>

namespace nonbloppy {

namespace {

/// The particle index's cell edge as a fraction of r_e, as in buildSurface().
constexpr double kCellOverRadius = 0.5;

void checkCancelled(openvdb::util::NullInterrupter* interrupter, const char* stage)
{
    if (interrupter && interrupter->wasInterrupted()) {
        throw CancelledError(std::string("interrupted during ") + stage);
    }
}

/// extractSurface() into @a mesh's existing vectors: volumeToMesh clears and resizes them,
/// which keeps their capacity. Same checks, orientation and result as extractSurface().
void extractSurfaceInto(const openvdb::FloatGrid& density, double threshold, double adaptivity,
                        SurfaceMesh& mesh)
{
    if (!std::isfinite(threshold) || !(adaptivity >= 0.0 && adaptivity <= 1.0)) {
        mesh = extractSurface(density, threshold, adaptivity);  // throws the usual error
        return;
    }
    openvdb::tools::volumeToMesh(density, mesh.points, mesh.triangles, mesh.quads, threshold,
                                 adaptivity);
    // The density grows inwards: reverse volumeToMesh's polygons to face outwards.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.quads.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t n = range.begin(); n < range.end(); ++n) {
                const openvdb::Vec4I q = mesh.quads[n];
                mesh.quads[n] = openvdb::Vec4I(q[3], q[2], q[1], q[0]);
            }
        });
    for (openvdb::Vec3I& t : mesh.triangles) std::swap(t[0], t[2]);
    mesh.normals.clear();
}

} // namespace

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
    {
        ScopedStageTimer timer(result.timings, "estimate parameters");
        if (mKeepParameters && mHaveKeptParameters) {
            result.parameters = mKeptParameters;
        } else {
            result.parameters = resolveParameters(mParams, mPositions);
            mKeptParameters = result.parameters;
            mHaveKeptParameters = true;
        }
    }
    const ResolvedParameters p = result.parameters;
    checkCancelled(interrupter, "estimate parameters");
    {
        ScopedStageTimer timer(result.timings, "index particles");
        // build() takes the vector over; positionBuffer() takes storage back next frame.
        mIndex = ParticleIndex::build(std::move(mPositions), kCellOverRadius * p.effectiveRadius);
        mPositions = std::vector<openvdb::Vec3f>();
    }
    checkCancelled(interrupter, "index particles");
    {
        ScopedStageTimer timer(result.timings, "rasterize density");
        DensitySettings settings;
        settings.effectiveRadius = p.effectiveRadius;
        settings.voxelSize = p.voxelSize;
        result.density = rasterizeDensity(mIndex, settings, interrupter);
        openvdb::FloatGrid& grid = *result.density;
        grid.insertMeta("effective_radius", openvdb::DoubleMetadata(p.effectiveRadius));
        grid.insertMeta("threshold", openvdb::DoubleMetadata(p.threshold));
        grid.insertMeta("blend", openvdb::DoubleMetadata(p.blend));
        grid.insertMeta("iterations", openvdb::Int32Metadata(p.iterations));
        grid.insertMeta("voxel_size", openvdb::DoubleMetadata(p.voxelSize));
        grid.insertMeta("spacing", openvdb::DoubleMetadata(p.spacing));
        grid.insertMeta("adaptivity", openvdb::DoubleMetadata(p.adaptivity));
        grid.insertMeta("method", openvdb::StringMetadata(p.method == Method::Paper ? "paper" : "faithful"));
        grid.insertMeta("particle_count", openvdb::Int64Metadata(int64_t(result.particleCount)));
        grid.insertMeta("nonbloppy_version", openvdb::StringMetadata(version()));
    }
    {
        ScopedStageTimer timer(result.timings, "extract surface");
        if (interrupter) interrupter->start("extract surface");
        if (!mParams.keepDensity) tileDeepInterior(*result.density, p.threshold);
        extractSurfaceInto(*result.density, p.threshold, p.adaptivity, result.mesh);
        if (!mParams.keepDensity) result.density.reset();
        if (interrupter) interrupter->end();
    }
    checkCancelled(interrupter, "extract surface");
    {
        ScopedStageTimer timer(result.timings, "relax vertices");
        RelaxSettings settings;
        settings.effectiveRadius = p.effectiveRadius;
        settings.blend = p.blend;
        settings.iterations = p.iterations;
        settings.maxStep = p.maxStep;
        // Positions before relaxation, for fold repair: a kept buffer.
        if (p.repairFolds) mUnrelaxed.assign(result.mesh.points.begin(), result.mesh.points.end());
        relaxVertices(result.mesh, mIndex, settings, interrupter);
    }
    if (p.repairFolds) {
        ScopedStageTimer timer(result.timings, "correct surface");
        repairFolds(result.mesh, mUnrelaxed);
    }
    {
        ScopedStageTimer timer(result.timings, "compute normals");
        computeNormals(result.mesh);
    }
    if (p.preserveVolume) {
        // Each particle stands for s³ of fluid; preserveVolume() recomputes the normals.
        ScopedStageTimer timer(result.timings, "correct surface");
        const double s = p.spacing;
        preserveVolume(result.mesh, double(result.particleCount) * s * s * s,
                       kMaxVolumeOffsetOverSpacing * s);
    }
    ++mFrames;
    return result;
}

} // namespace nonbloppy
