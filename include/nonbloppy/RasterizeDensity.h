// SPDX-License-Identifier: Apache-2.0
/// @file RasterizeDensity.h
/// @brief Stage "rasterize density": φ(x) = Σ_j w(|x − r_j|) into a sparse openvdb::FloatGrid.

#ifndef NONBLOPPY_RASTERIZE_DENSITY_H
#define NONBLOPPY_RASTERIZE_DENSITY_H

#include <nonbloppy/Export.h>
#include <nonbloppy/ParticleIndex.h>

#include <openvdb/openvdb.h>
#include <openvdb/util/NullInterrupter.h>

namespace nonbloppy {

/// The most voxels per effective radius (r_e/h) rasterizeDensity() accepts. An isolated
/// particle's support holds (4π/3)(r_e/h)³ voxels, 137k at this limit (0.6 MB of grid); at
/// r_e/h = 1000 it would be 4·10⁹ voxels, 18 GB, for one particle.
constexpr double kMaxVoxelsPerRadius = 32.0;

/// How the density is sampled.
struct DensitySettings
{
    double effectiveRadius = 0.0;  ///< r_e, world units, > 0
    double voxelSize = 0.0;        ///< h, world units, > 0; ignored when transform is set
    /// Optional caller-provided transform (voxel centres are sampled). It must be a
    /// uniform scale (Transform::createLinearTransform(h)): voxel centres at integer
    /// multiples of h. When null, such a transform of voxelSize is made.
    openvdb::math::Transform::Ptr transform;
};

/// Sample the MPS density at every voxel centre within r_e of some particle.
///
/// The result is a FloatGrid named "density", class GRID_FOG_VOLUME (φ grows inwards, so
/// it is not a level set), background 0; exactly the voxels within r_e of a particle are
/// active. Each column, up to 4 × 4 stacks of 8 leaves along z, is filled by one task from
/// the particles whose support overlaps it, visited in a fixed order, so values are
/// bit-identical for any thread count (and for any grouping of leaves into columns).
/// Cost: O(N·(r_e/h)³) kernel evaluations; memory: the grid (≈ 4.5 bytes per active voxel).
/// @param particles    the particle index (its cell size does not affect the result)
/// @param settings     r_e and h in world units, or a caller's transform
/// @param interrupter  optional; start("rasterize density"), then wasInterrupted() every
///                     64 particle-index leaves in each of the two passes that count and
///                     list the candidate leaves, every 1 ms
///                     (from a helper thread) while sorting them, before each column once
///                     8 density leaves of the task are done (~0.1–1 ms of work) with
///                     wasInterrupted(percent) at each task's end, every 4096 leaves
///                     while assembling the tree; end().
///                     After a stop the partial grid is freed.
/// Thread-safety: reentrant; the index is only read.
/// @throw ParameterError if r_e or h is not finite or ≤ 0, r_e > 1e18 (lengths are squared
///        in single precision), h < kMinCellSize, a given
///        transform is not a uniform scale, r_e/h > kMaxVoxelsPerRadius, or @a particles
///        holds particles in cells outside kMinCellsPerRadius..kMaxCellsPerRadius of r_e,
///        or, before anything is allocated, if even half the bytes of the candidate leaves
///        (and their internal nodes) exceed what the process can still take (the machine's
///        memory, ulimit -v or -d, or its cgroup's memory.max, less what it holds: "the
///        density grid (up to N leaves of 8^3 voxels) of these particles at --voxel-size h
///        and --radius r would take A GB to B GB, more than the C GB this process can still
///        take: ..."); CancelledError if @a interrupter says so.
NONBLOPPY_API openvdb::FloatGrid::Ptr rasterizeDensity(const ParticleIndex& particles,
                                         const DensitySettings& settings,
                                         openvdb::util::NullInterrupter* interrupter = nullptr);

} // namespace nonbloppy

#endif // NONBLOPPY_RASTERIZE_DENSITY_H
