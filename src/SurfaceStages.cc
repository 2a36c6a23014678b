// SPDX-License-Identifier: Apache-2.0
/// @file SurfaceStages.cc
/// @brief The stage chain shared by buildSurface() and SurfaceReconstructor.

#include "SurfaceStages.h"

#include "Cancellation.h"
#include "OpenVdbScale.h"
#include "UnwrittenVector.h"

#include <nonbloppy/ComputeNormals.h>
#include <nonbloppy/CorrectSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/ExtractSurface.h>
#include <nonbloppy/RasterizeDensity.h>
#include <nonbloppy/RelaxVertices.h>
#include <nonbloppy/SmoothSurface.h>
#include <nonbloppy/Version.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstring>
#include <string>

namespace nonbloppy {
namespace surface_stages_internal {

void requireParticles(const std::vector<openvdb::Vec3f>& positions)
{
    if (positions.empty()) throw ParameterError("no particles to mesh");
}

void checkCancelled(openvdb::util::NullInterrupter* interrupter, const char* stage)
{
    cancellation_internal::CancelPoll(interrupter, stage).throwIfStopped();
}

void resolveAndIndex(const SurfaceParameters& params, const ResolvedParameters* kept,
                     std::vector<openvdb::Vec3f>& positions, ParticleIndex& index, SurfaceResult& result,
                     openvdb::util::NullInterrupter* interrupter)
{
    requireParticles(positions);  // kept parameters skip resolveParameters(), which checks it too
    const auto indexParticles = [&](double effectiveRadius) {
        StageScope scope(result.timings, interrupter, "index particles");
        index = ParticleIndex::build(std::move(positions), kCellOverRadius * effectiveRadius, interrupter);
        positions = std::vector<openvdb::Vec3f>();  // moved from: empty, not unspecified
        checkCancelled(interrupter, "index particles");
    };
    const bool indexFirst = !kept && params.effectiveRadius && *params.effectiveRadius > 0.0
                            && std::isfinite(*params.effectiveRadius);
    if (indexFirst) {
        openvdb_scale_internal::requireOpenVdbScale(*params.effectiveRadius, kMinCellSize / kCellOverRadius, "--radius");
        indexParticles(*params.effectiveRadius);
    }
    {
        StageScope scope(result.timings, interrupter, "estimate parameters");
        result.parameters = kept ? *kept
                          : indexFirst ? resolveParametersIndexed(params, index, interrupter)
                                       : resolveParameters(params, positions, interrupter);
        checkCancelled(interrupter, "estimate parameters");
    }
    if (!indexFirst) indexParticles(result.parameters.effectiveRadius);
    result.particleBounds = index.bounds();
}

namespace {

/// @a points copied into @a unrelaxed by both threads. A serial copy (vector::assign) of the
/// 64x benchmark mesh's 2.4M vertices took 15 ms of one core as relaxation started, most of
/// it first-touch page faults of the new buffer, while the other core waited.
template<typename VertexBufferT>
void copyInParallel(const std::vector<openvdb::Vec3s>& points, VertexBufferT& unrelaxed)
{
    unrelaxed.resize(points.size());
    openvdb::Vec3s* to = unrelaxed.data();
    const openvdb::Vec3s* from = points.data();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), size_t(1) << 16),
                      [&](const tbb::blocked_range<size_t>& range) {
                          std::memcpy(static_cast<void*>(to + range.begin()), from + range.begin(),
                                      range.size() * sizeof(openvdb::Vec3s));
                      });
}

} // namespace

template<typename VertexBufferT>
void runSurfaceStages(const ParticleIndex& index, const SurfaceParameters& params, SurfaceResult& result,
                      VertexBufferT& unrelaxed, UnrelaxedBuffer whenRepaired,
                      openvdb::util::NullInterrupter* interrupter)
{
    const ResolvedParameters p = result.parameters;
    const auto rasterize = [&] {
        ScopedStageTimer timer(result.timings, "rasterize density");
        DensitySettings settings;
        settings.effectiveRadius = p.effectiveRadius;
        settings.voxelSize = p.voxelSize;
        result.density = rasterizeDensity(index, settings, interrupter);
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
    };
    rasterize();
    bool wholeGrid = false;
    {
        StageScope scope(result.timings, interrupter, "extract surface");
        // Region by region (adaptivity 0): volumeToMesh cannot be stopped safely from
        // outside (see Cancellation.h), so the regions bound the wait for a cancel.
        // A grid nobody keeps gives its memory back as the regions pass.
        try {
            extractSurfaceInto(*result.density, p.threshold, p.adaptivity, p.regionLeaves, result.mesh, interrupter,
                               params.keepDensity ? nullptr : &result.density->tree(), params.trimFreedMemory);
        } catch (const AmbiguousSeamError&) {
            wholeGrid = true;
        }
        if (!wholeGrid) {
            if (!params.keepDensity) result.density.reset();
            checkCancelled(interrupter, "extract surface");
        }
    }
    if (wholeGrid) {
        // Seam vertices that only their cells tell apart, found after leaves were freed
        // (so keepDensity is false): the grid again (the partial one freed first), meshed
        // whole (uninterruptible, as regionLeaves = 0 is), and freed.
        result.density.reset();
        rasterize();
        StageScope scope(result.timings, interrupter, "extract surface");
        extractSurfaceInto(*result.density, p.threshold, p.adaptivity, 0, result.mesh, interrupter);
        result.density.reset();
        checkCancelled(interrupter, "extract surface");
    }
    {
        ScopedStageTimer timer(result.timings, "relax vertices");
        RelaxSettings settings;
        settings.effectiveRadius = p.effectiveRadius;
        settings.blend = p.blend;
        settings.iterations = p.iterations;
        settings.maxStep = p.maxStep;
        if (p.repairFolds) copyInParallel(result.mesh.points, unrelaxed);
        relaxVertices(result.mesh, index, settings, interrupter);
    }
    if (p.repairFolds) {
        StageScope scope(result.timings, interrupter, "correct surface");
        repairFoldsUnchecked(result.mesh, unrelaxed.data(), kDefaultRepairRounds, interrupter);
        // Large frames peak while the normals are computed: give the copy back first.
        if (whenRepaired == UnrelaxedBuffer::Release) VertexBufferT().swap(unrelaxed);
        checkCancelled(interrupter, "correct surface");
    }
    {
        StageScope scope(result.timings, interrupter, "compute normals");
        computeNormals(result.mesh, interrupter);
        checkCancelled(interrupter, "compute normals");
    }
    // The volume offset moves each vertex along its normal, and the smoothing moves it again:
    // slivers between neighbours moved by different amounts turned over, 4% of the triangles
    // of the dam-break frame at --spacing 0.0467 (bug hunt). With fold repair each of the two
    // is checked against the surface it started from, and the vertices of what it turned
    // over go back towards it: 0.35% are left. One check against the relaxed surface after
    // both left 0.03%, but its reverted vertices lost offset and smoothing alike (up to
    // 0.96 s) and the largest errors of docs/fidelity.md grew up to 2.4 times; this way by
    // up to 15% (7% with the default options).
    const auto repairAgainstStart = [&] {
        if (repairFoldsUnchecked(result.mesh, unrelaxed.data(), kDefaultRepairRounds, interrupter) > 0) {
            computeNormals(result.mesh, interrupter);
        }
    };
    if (p.preserveVolume) {
        // Each particle stands for s³ of fluid; preserveVolume() recomputes the normals.
        StageScope scope(result.timings, interrupter, "correct surface");
        if (p.repairFolds) copyInParallel(result.mesh.points, unrelaxed);  // past the normals' peak
        const double s = p.spacing;
        VolumeSettings volume;
        volume.targetVolume = double(result.particleCount) * s * s * s;
        volume.offset = p.volumeOffset;
        volume.convexityFloor = kConvexityFloorOverSpacing * s;
        volume.maxDistance = (p.volumeOffset == VolumeOffset::Convex ? kMaxConvexOffsetOverSpacing
                                                                     : kMaxVolumeOffsetOverSpacing) * s;
        preserveVolumeUnchecked(result.mesh, volume, interrupter);
        if (p.repairFolds) repairAgainstStart();
        checkCancelled(interrupter, "correct surface");
    }
    if (p.smoothSurface) {
        // After the volume correction: smoothing first would leave the edges it rounds
        // nothing to put their volume back (docs/fidelity.md).
        StageScope scope(result.timings, interrupter, "smooth surface");
        if (p.repairFolds) copyInParallel(result.mesh.points, unrelaxed);
        SmoothSettings settings;
        settings.spatialWidth = kDefaultSmoothWidthOverSpacing * p.spacing;
        smoothSurfaceUnchecked(result.mesh, settings, interrupter);
        computeNormals(result.mesh, interrupter);
        if (p.repairFolds) repairAgainstStart();
        checkCancelled(interrupter, "smooth surface");
    }
    if (p.repairFolds && (p.preserveVolume || p.smoothSurface) && whenRepaired == UnrelaxedBuffer::Release) {
        VertexBufferT().swap(unrelaxed);
    }
}

template void runSurfaceStages(const ParticleIndex&, const SurfaceParameters&, SurfaceResult&, std::vector<openvdb::Vec3s>&,
                               UnrelaxedBuffer, openvdb::util::NullInterrupter*);
template void runSurfaceStages(const ParticleIndex&, const SurfaceParameters&, SurfaceResult&,
                               memory_internal::UnwrittenVector<openvdb::Vec3s>&, UnrelaxedBuffer,
                               openvdb::util::NullInterrupter*);

} // namespace surface_stages_internal
} // namespace nonbloppy
