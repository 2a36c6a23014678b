// SPDX-License-Identifier: Apache-2.0
/// @file CorrectSurface.h
/// @brief Stage "correct surface": what the paper's relaxation needs to stay faithful to the
///        fluid's true surface (the particles grown by s/2): an iso-value calibrated for the
///        relaxed surface, repair of folded triangles, and an optional volume correction.
///
/// Relaxing pulls every vertex towards the particle centres: with c = 0.3, t = 2 a flat face
/// ends 0.32 s inside the true surface, and the fluid loses that much all around
/// (docs/fidelity.md, row "paper"). buildSurface() with Method::Faithful extracts at
/// calibrateRelaxedThreshold() instead, so that relaxation ends on the true surface, then
/// calls repairFolds() and, given the spacing, preserveVolume(); Method::Paper calls none of this.

#ifndef NONBLOPPY_CORRECT_SURFACE_H
#define NONBLOPPY_CORRECT_SURFACE_H

#include <nonbloppy/Export.h>
#include <nonbloppy/Mesh.h>

#include <openvdb/openvdb.h>
#include <openvdb/util/NullInterrupter.h>

#include <cstddef>
#include <limits>
#include <vector>

namespace nonbloppy {

/// The iso-value r_0 for which the surface of a flat, uniform half-space of particles on a
/// cubic lattice of spacing s ends, after @a iterations relaxation steps of blend @a blend,
/// s/2 outside the outer particle layer (averaged over the lattice cell), so the relaxed
/// fluid's volume is about N·s³. With t = 0 or c = 0 it equals calibrateThreshold().
/// The start height is limited to min(1.5 s, 0.75 r_e): relaxations so strong that they
/// would need to start farther out (uncapped, c = 0.5, t = 2 would start 1.9 s out and
/// merge fluid bodies 4 s apart; with the default cap of s/2 it starts just within reach,
/// while c = 0.4, t = 3 does not) get the threshold of that limit and end inside the true
/// surface.
/// The result depends only on r_e/s, c, t and the cap. Cost: about 10⁵ kernel evaluations
/// (2 ms at r_e = 2.1 s), growing as (r_e/s)³ and with t, up to the step where a sample
/// vertex stops moving.
/// Thread-safety: reentrant.
/// @param effectiveRadiusOverSpacing  r_e / s, > 0.5
/// @param blend           c in [0,1]
/// @param iterations      t ≥ 0
/// @param reachesSurface  optional; set to whether the relaxed face ends at s/2 (false when
///                        the start height had to be limited and the face ends inside)
/// @param maxStepOverSpacing  the relaxation's cap on one step (RelaxSettings::maxStep) in
///                        units of s; 0 or +inf: uncapped. The calibration takes the same capped
///                        steps as the mesh will: a start 1.4 s out (r_e = 2 s, c = 0.4,
///                        t = 2) needs steps longer than the default cap of s/2, and
///                        calibrating for uncapped ones left the box's faces 0.09 s off.
/// @throw ParameterError if @a effectiveRadiusOverSpacing ≤ 0.5 or above
///        kMaxCalibratedRadiusOverSpacing, c outside [0,1], t < 0 or @a maxStepOverSpacing < 0
///        or NaN.
NONBLOPPY_API double calibrateRelaxedThreshold(double effectiveRadiusOverSpacing, double blend,
                                               int iterations, bool* reachesSurface = nullptr,
                                               double maxStepOverSpacing = 0.0);

/// Number of triangles (quads split along the 0–2 diagonal) of @a mesh whose normal points
/// against the normal the same triangle had with the vertex positions @a before (same
/// polygons): the triangles relaxation folded over.
/// Cost: O(P). Thread-safety: reentrant.
/// @throw ParameterError if @a before and mesh.points differ in size, or naming the first
///        polygon with a corner out of range ("polygon P references vertex I but the mesh
///        has N vertices"; triangles are numbered first, then quads, as the writers do).
NONBLOPPY_API size_t countFoldedTriangles(const SurfaceMesh& mesh, const std::vector<openvdb::Vec3s>& before);

/// Rounds of halving that repairFolds() tries before moving vertices all the way back.
constexpr int kDefaultRepairRounds = 4;

/// Unfold triangles folded over by relaxation: every vertex of a folded triangle (see
/// countFoldedTriangles()) is moved halfway back to its position in @a before, and this is
/// repeated until no triangle is folded or @a maxRounds rounds have run; the vertices of
/// triangles still folded then go all the way back. Vertices of unfolded triangles are not
/// touched, so a mesh without folds is returned bit for bit.
/// @return the number of folded triangles found in the first round
/// @param mesh         relaxed mesh; vertices of folded triangles moved back
/// @param before       vertex positions before relaxation (same count as mesh.points)
/// @param maxRounds    halving rounds before the last resort of moving all the way back
/// @param interrupter  optional; asked every 4096 polygons of each task of each round, no
///                     start()/end() (buildSurface() announces "correct surface"); a stop
///                     leaves the vertices partly repaired
/// Cost: O(rounds · P), parallel over polygons. Deterministic. Normals are not updated.
/// Thread-safety: reentrant; the mesh is written.
/// @throw ParameterError if @a before and mesh.points differ in size, maxRounds < 0
///        ("fold repair rounds must be >= 0, got -5") or a polygon has a corner out of
///        range (as countFoldedTriangles(); checked before anything moves);
///        CancelledError("interrupted during correct surface") when @a interrupter says stop.
NONBLOPPY_API size_t repairFolds(SurfaceMesh& mesh, const std::vector<openvdb::Vec3s>& before,
                                 int maxRounds = kDefaultRepairRounds,
                                 openvdb::util::NullInterrupter* interrupter = nullptr);

/// Move every vertex by @a distance (world units, > 0 outwards) along its unit normal, which
/// must have been computed (computeNormals()); vertices with a zero normal stay put.
/// @throw ParameterError if @a distance is not finite ("offset distance must be finite, got
///        nan") or mesh.normals and mesh.points differ in size.
NONBLOPPY_API void offsetSurface(SurfaceMesh& mesh, double distance);

/// How preserveVolume() spreads its offset over the surface.
enum class VolumeOffset
{
    /// Every vertex moves the same distance along its normal. Simple, but relaxation takes
    /// its volume mostly from edges, corners and thin features, so a uniform offset pushes
    /// the flat faces out to pay for them (docs/fidelity.md, row "uniform volume offset").
    Uniform,
    /// Each vertex moves in proportion to how convex the surface is there: its convexity
    /// (the distance from the mean of its edge neighbours to the vertex, along the normal)
    /// above a floor that ignores the bumps of flat faces. The volume goes back where
    /// relaxation took it: rounded edges and corners grow back towards sharp ones, thin
    /// sheets and jets regain their thickness, flat faces stay where they are.
    Convex,
};

/// What preserveVolume() aims for and how it may move the surface.
struct VolumeSettings
{
    double targetVolume = 0.0;                ///< volume to enclose, world units³, > 0
    VolumeOffset offset = VolumeOffset::Convex;  ///< how the offset is spread
    /// Convex only: convexity below this (world units, ≥ 0) counts as flat and does not move.
    double convexityFloor = 0.0;
    /// Largest distance any vertex moves in total, world units (> 0): a wrong target cannot
    /// move the surface far.
    double maxDistance = std::numeric_limits<double>::infinity();
};

/// Offset the surface along its normals (offsetSurface()) so that its enclosed volume becomes
/// @a targetVolume (world units³), to first order: distance = (target − volume) / area,
/// applied twice to absorb the curvature term. Needs normals; recomputes them afterwards.
/// Only meaningful for a closed mesh whose target is known (e.g. N·s³ for an incompressible
/// fluid of N particles at spacing s); a wrong target shifts the whole surface.
/// @return the total distance moved along the normals (world units)
/// @throw ParameterError if targetVolume or maxDistance is not > 0, normals are missing or
///        a polygon has a corner out of range (as countFoldedTriangles());
///        CancelledError("interrupted during correct surface") when @a interrupter says stop.
/// @param mesh         closed mesh with normals; vertices moved, normals recomputed
/// @param targetVolume volume to enclose, world units³, > 0
/// @param maxDistance  largest distance moved in total, world units (the correction is
///                     clamped to ±maxDistance, so a wrong target cannot move the surface far)
/// @param interrupter  optional; asked before and after each measureAreaAndVolume() (which
///                     is serial and not interruptible, O(P)) and inside computeNormals() as there;
///                     no start()/end(). A stop leaves the mesh partly offset.
/// Cost: two passes of measureAreaAndVolume() + offsetSurface() + computeNormals(), O(P + V).
/// Thread-safety: reentrant; the mesh is written.
NONBLOPPY_API double preserveVolume(SurfaceMesh& mesh, double targetVolume,
                                    double maxDistance = std::numeric_limits<double>::infinity(),
                                    openvdb::util::NullInterrupter* interrupter = nullptr);

/// Offset the surface along its normals so that it encloses settings.targetVolume, spreading
/// the offset as settings.offset says. Uniform is preserveVolume() above. Convex computes
/// every vertex's convexity once, moves vertex i by α·max(0, convexity_i − convexityFloor)
/// with α solved from the volume and the vertices' areas (three passes, absorbing the
/// curvature term), each vertex's total clamped to ±maxDistance; if no vertex is convex
/// enough it falls back to Uniform. Faithful buildSurface() uses Convex with a floor of
/// kConvexityFloorOverSpacing·s: on the fidelity shapes, with the default smoothing, it
/// brings the mean distance to the true surface 1.05x (ball) to 2.7x (jet) closer than
/// Uniform (docs/fidelity.md).
/// @return the signed distance of the vertex that moved farthest (world units, < 0 inwards)
/// @throw ParameterError if the target is not > 0, the floor is < 0, maxDistance is not > 0,
///        the offset is not a VolumeOffset enumerator, normals are missing or a polygon has
///        a corner out of range (as countFoldedTriangles(); checked before anything moves);
///        CancelledError("interrupted during correct surface") when @a interrupter says
///        stop (asked every 4096 polygons of the convexity pass, between blocks of 16,384
///        polygons of each measuring pass and inside computeNormals(); a stop leaves the
///        mesh partly offset).
/// Cost: Convex: one serial pass over the polygons for the convexity, then per pass the
/// area, volume and vertex areas (O(P): the per-triangle terms in parallel, their sums in
/// polygon order, so the same bits as measureAreaAndVolume()), the offset and
/// computeNormals(); scratch up to 36 bytes per vertex (while the convexity is measured), 24
/// after, plus 24 bytes per triangle of the blocks in flight. Deterministic. Thread-safety:
/// reentrant; the mesh is written.
NONBLOPPY_API double preserveVolume(SurfaceMesh& mesh, const VolumeSettings& settings,
                                    openvdb::util::NullInterrupter* interrupter = nullptr);

} // namespace nonbloppy

#endif // NONBLOPPY_CORRECT_SURFACE_H
