// SPDX-License-Identifier: Apache-2.0
/// @file SmoothSurface.h
/// @brief Stage "smooth surface": feature-preserving smoothing of the relaxed, volume-corrected
///        surface (bilateral filtering of the face normals, then vertices fitted to them).
///
/// Relaxation pulls each vertex onto the weighted mean of the particles near it, so the mesh
/// follows their jitter and, on curved fluid, the lattice's staircase: on the jittered box of
/// docs/fidelity.md the relaxed mesh lies 0.033 s from the true surface on average, blobs
/// (which average the jitter away but round the edges) 0.050 s. A bilateral filter of the
/// face normals averages normals only with neighbours that point nearly the same way, so flat faces and
/// gentle curves get smooth while the 90° normal jump of an edge or a corner is left alone;
/// the vertices are then moved, along the filtered normals only, onto the planes of their
/// faces (Zheng et al. 2011, "Bilateral normal filtering for mesh denoising", local scheme,
/// and Sun et al. 2007's vertex update).
///
/// It keeps edges that are sharp, not edges that relaxation left rounded: across a rounded
/// edge the normal turns a little from face to face, and the filter spreads the rounding.
/// The defaults (c = 0.3, t = 2) relax the edges sharp; docs/fidelity_sweep.md shows the other
/// settings, some of which (c = 0.3, t = 1; c = 0.4, t = 2) leave the box farther from the
/// truth with the smoothing than without.

#ifndef NONBLOPPY_SMOOTH_SURFACE_H
#define NONBLOPPY_SMOOTH_SURFACE_H

#include <nonbloppy/Export.h>
#include <nonbloppy/Mesh.h>

#include <openvdb/util/NullInterrupter.h>

namespace nonbloppy {

/// Default spatial width of the normal filter, in units of the particle spacing s.
constexpr double kDefaultSmoothWidthOverSpacing = 0.7;
/// Default width of the normal filter's range weight, in units of |n_i − n_j| (dimensionless):
/// 0.3 weighs a 10° neighbour 0.84, a 45° one 0.04 and a 90° one (a box's edge) 1.5·10⁻⁵.
constexpr double kDefaultNormalWidth = 0.3;
/// Default rounds of normal filtering: each round reaches one ring of faces further.
constexpr int kDefaultNormalRounds = 35;
/// Default rounds of moving the vertices onto the filtered face planes.
constexpr int kDefaultVertexRounds = 40;

/// How smoothSurface() filters. The defaults were chosen on the shapes of docs/fidelity.md
/// (meshed at h = s/2): with them, after the volume correction, the mean distance to the true
/// surface is 2.3–5.2x lower than blobs' on the box, slab, ball and jet.
struct SmoothSettings
{
    /// σ_c, world units, > 0: face normals are weighted by exp(−d²/2σ_c²) with d the distance
    /// between the faces' centroids. buildSurface() uses kDefaultSmoothWidthOverSpacing·s.
    double spatialWidth = 0.0;
    /// σ_r, > 0: and by exp(−|n_i − n_j|²/2σ_r²), so that faces across an edge do not mix.
    double normalWidth = kDefaultNormalWidth;
    int normalRounds = kDefaultNormalRounds;  ///< ≥ 0; 0 leaves the mesh as it is
    int vertexRounds = kDefaultVertexRounds;  ///< ≥ 0; 0 leaves the mesh as it is
};

/// Smooth @a mesh without rounding its edges. Its polygons, triangles and quads alike, are the
/// faces: a face's normal and area are those of its vector area (for a quad, half the cross
/// product of its diagonals), its centroid the mean of its corners. Each normal round
/// replaces every face's unit normal n_i by the normalized sum, over the faces j sharing a
/// vertex with it (weighted by the number of vertices shared, itself included), of
/// area_j · exp(−|c_i − c_j|²/2σ_c² − |n_i − n_j|²/2σ_r²) · n_j, with the centroids c and areas
/// of the unsmoothed mesh. Each vertex round then moves every vertex v by the mean over its
/// faces of n_j (n_j · (c_j − v)), c_j from the previous round. Vertices move only along the
/// filtered normals; the polygons are not changed. A mesh without polygons is left as it
/// is. Normals are not updated (computeNormals() after).
/// Cost: once, the list of each face's neighbours (9 for a quad of a regular grid, found by
/// sorting the faces around its corners) with the spatial part of their weights; then per
/// normal round one exponential per neighbour (eight faces at a time where the CPU has
/// AVX2, sixteen where it has AVX-512F), per vertex round one pass over the faces around each
/// vertex. Parallel over faces and vertices. Scratch about 145 bytes per quad. On the 64x
/// benchmark input's surface (2.39M vertices, 2.37M quads, `--spacing 0.0467157`, two
/// threads) the defaults take 2.07–2.10 s on an AVX-512 AMD EPYC (Zen 4) VM: setup about
/// 0.4 s, the 35 normal rounds about 23 ms each (55 ms when each lane gathered its
/// neighbours' indices, weights and normals, 3.49–4.00 s in all), the 40 vertex rounds about
/// 22 ms each (31 ms one vertex at a time). Deterministic: each element reads only
/// the previous round, in a fixed order, so the result is the same bits for any thread count.
/// @param mesh         vertices moved; polygon indices must be valid (see measureMesh())
/// @param settings     the filter's widths and rounds; spatialWidth has no default
/// @param interrupter  optional; asked every 4096 elements of each parallel task (no
///                     start()/end(): buildSurface() announces "smooth surface"); a stop
///                     leaves the vertices where the last finished round put them
/// Thread-safety: reentrant; the mesh is written.
/// @throw ParameterError("polygon P references vertex I but the mesh has N vertices") for
///        the first polygon with a corner out of range (triangles first, then quads; checked
///        before anything moves), or naming the setting if a width is not > 0 or finite,
///        or a round count is < 0; ParameterError("smoothing the surface (N polygons) would
///        take another X, more than the Y this process can still take: give --no-smooth to
///        skip it"), before the scratch is allocated, where it would not fit in what the
///        machine, ulimit -v or -d, or the memory cgroup still allow; CancelledError
///        ("interrupted during smooth surface") when @a interrupter says stop.
NONBLOPPY_API void smoothSurface(SurfaceMesh& mesh, const SmoothSettings& settings,
                                 openvdb::util::NullInterrupter* interrupter = nullptr);

} // namespace nonbloppy

#endif // NONBLOPPY_SMOOTH_SURFACE_H
