// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/BuildSurface.h>
#include <nonbloppy/ComputeNormals.h>
#include <nonbloppy/CorrectSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/ExtractSurface.h>
#include <nonbloppy/ParticleIndex.h>
#include <nonbloppy/RasterizeDensity.h>
#include <nonbloppy/RelaxVertices.h>
#include <nonbloppy/Version.h>

namespace nonbloppy {

namespace {

/// The particle index's cell edge as a fraction of r_e: a search box of ±r_e then spans about
/// five cells per axis, which wastes less work on particles outside the support sphere than
/// cells of r_e (three per axis, 27 r_e³ visited for a 4.2 r_e³ sphere).
constexpr double kCellOverRadius = 0.5;

void checkCancelled(openvdb::util::NullInterrupter* interrupter, const char* stage)
{
    if (interrupter && interrupter->wasInterrupted()) {
        throw CancelledError(std::string("interrupted during ") + stage);
    }
}

} // namespace

SurfaceResult buildSurface(std::vector<openvdb::Vec3f> positions, const SurfaceParameters& params,
                           openvdb::util::NullInterrupter* interrupter)
{
    SurfaceResult result;
    result.particleCount = positions.size();
    {
        ScopedStageTimer timer(result.timings, "estimate parameters");
        result.parameters = resolveParameters(params, positions);
    }
    const ResolvedParameters& p = result.parameters;
    checkCancelled(interrupter, "estimate parameters");

    ParticleIndex index;
    {
        ScopedStageTimer timer(result.timings, "index particles");
        index = ParticleIndex::build(std::move(positions), kCellOverRadius * p.effectiveRadius);
    }
    checkCancelled(interrupter, "index particles");
    {
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
    }
    {
        ScopedStageTimer timer(result.timings, "extract surface");
        if (interrupter) interrupter->start("extract surface");
        if (!params.keepDensity) tileDeepInterior(*result.density, p.threshold);
        result.mesh = extractSurface(*result.density, p.threshold, p.adaptivity);
        if (!params.keepDensity) result.density.reset();
        if (interrupter) interrupter->end();
    }
    checkCancelled(interrupter, "extract surface");
    std::vector<openvdb::Vec3s> unrelaxed;  // positions before relaxation, for fold repair
    {
        ScopedStageTimer timer(result.timings, "relax vertices");
        RelaxSettings settings;
        settings.effectiveRadius = p.effectiveRadius;
        settings.blend = p.blend;
        settings.iterations = p.iterations;
        settings.maxStep = p.maxStep;
        if (p.repairFolds) unrelaxed = result.mesh.points;
        relaxVertices(result.mesh, index, settings, interrupter);
    }
    if (p.repairFolds) {
        ScopedStageTimer timer(result.timings, "correct surface");
        repairFolds(result.mesh, unrelaxed);
        std::vector<openvdb::Vec3s>().swap(unrelaxed);
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
    return result;
}

} // namespace nonbloppy
