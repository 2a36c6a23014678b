// SPDX-License-Identifier: Apache-2.0
/// @file RelaxVertices.h
/// @brief Stage "relax vertices": pull mesh vertices towards the kernel-weighted mean of
///        nearby particles, which flattens faces, sharpens edges and keeps sheets thin.

#ifndef NONBLOPPY_RELAX_VERTICES_H
#define NONBLOPPY_RELAX_VERTICES_H

#include <nonbloppy/Export.h>
#include <nonbloppy/Mesh.h>
#include <nonbloppy/ParticleIndex.h>

#include <openvdb/util/NullInterrupter.h>

namespace nonbloppy {

/// Relaxation parameters.
struct RelaxSettings
{
    double effectiveRadius = 0.0;  ///< r_e, world units, > 0 (the kernel's support)
    double blend = 0.3;            ///< c in [0,1]: 0 leaves vertices alone, 1 jumps to the mean
    int iterations = 2;            ///< t ≥ 0
    /// Cap on how far one iteration may move a vertex, world units: a longer step keeps its
    /// direction and is shortened to maxStep. 0 (the default) or +inf is the paper's
    /// uncapped step.
    /// Guards against spikes where a vertex sees only a few particles.
    double maxStep = 0.0;
};

/// Apply t times, to every vertex v_i of @a mesh:
///   t_i = Σ_j w(|v_i − r_j|) r_j / Σ_j w(|v_i − r_j|),   v_i ← (1 − c) v_i + c t_i.
/// Each iteration reads only the previous iteration's positions, so the result does not
/// depend on thread count or order. A vertex with no particle within r_e stays put.
/// A vertex's step depends only on its own position, so vertices are relaxed group by group
/// (vertices that share a cell), each group taking all t steps while it is in cache.
/// Normals are not updated (call computeNormals() afterwards).
/// Cost: t · V · (particles within r_e) kernel evaluations, parallel over vertex groups;
/// scratch memory about 20 bytes per vertex (the grouping).
/// @param mesh         vertices moved in place (world units); polygons untouched
/// @param particles    index of the particles to relax against (any frame's, any mesh's)
/// @param settings     r_e (world units), c, t
/// @param interrupter  optional; start("relax vertices"), then wasInterrupted() every 4096
///                     vertices while grouping them by cell (once, before relaxing) and
///                     every 1 ms (from a helper thread) if that takes the parallel sort,
///                     then every 16 vertex groups of each task and wasInterrupted(percent)
///                     after it; end(), also when it throws. A stop leaves every vertex
///                     either where it was or fully relaxed (t steps).
/// Thread-safety: reentrant; the index is only read, the mesh is written.
/// @throw ParameterError for r_e ≤ 0 or > 1e18, c outside [0,1], t < 0, maxStep < 0, or @a particles
///        holding particles in cells outside kMinCellsPerRadius..kMaxCellsPerRadius of r_e;
///        CancelledError("interrupted during relax vertices") on interrupt.
NONBLOPPY_API void relaxVertices(SurfaceMesh& mesh, const ParticleIndex& particles,
                   const RelaxSettings& settings,
                   openvdb::util::NullInterrupter* interrupter = nullptr);

} // namespace nonbloppy

#endif // NONBLOPPY_RELAX_VERTICES_H
