// SPDX-License-Identifier: Apache-2.0
/// @file InterpolateAttributes.h
/// @brief Stage "interpolate attributes": carry named particle attributes (velocity for
///        motion blur, ids, temperatures...) to the vertices of the final mesh.
///
/// @code
/// nonbloppy::ParticleSet particles = nonbloppy::readParticles("frame.bgeo");
/// nonbloppy::SurfaceResult result = nonbloppy::buildSurface(particles.positions, params);
/// nonbloppy::interpolateAttributes(result.mesh, particles, {"velocity"},
///                                  result.parameters.effectiveRadius);
/// nonbloppy::writeMesh(result.mesh, "frame.ply");   // velocity as PLY vertex properties
/// @endcode

#ifndef NONBLOPPY_INTERPOLATE_ATTRIBUTES_H
#define NONBLOPPY_INTERPOLATE_ATTRIBUTES_H

#include <nonbloppy/Export.h>
#include <nonbloppy/Mesh.h>
#include <nonbloppy/Particles.h>

#include <openvdb/util/NullInterrupter.h>

#include <string>
#include <vector>

namespace nonbloppy {

/// The attribute names @a requested resolved against @a particles: "all" (alone) gives every
/// attribute in file order; otherwise each name must exist.
/// @throw ParameterError "unknown attribute 'x'; the particles have: velocity, id" (or
///        "...; the particles have no attributes").
NONBLOPPY_API std::vector<std::string> resolveAttributeNames(const ParticleSet& particles,
                                               const std::vector<std::string>& requested);

/// The attributes of @a particles named in @a names (as resolveAttributeNames() takes them),
/// checked as interpolateAttributes() checks them before any work, so a caller can refuse a
/// frame before meshing it. Cost: O(N) for a UInt64 attribute (its values are scanned), O(1)
/// otherwise.
/// @throw ParameterError as resolveAttributeNames(); "attribute 'c' has 1 values for 1000
///        particles"; "attribute 'h' holds 18446744073709551615, above 9223372036854775807,
///        the largest integer a mesh attribute holds" (a UInt64 past int64).
NONBLOPPY_API std::vector<const ParticleAttribute*> checkAttributes(const ParticleSet& particles,
                                                                  const std::vector<std::string>& names);

/// Append to mesh.attributes, for each attribute of @a particles named in @a names, its
/// values at every vertex v_i of @a mesh (as positioned now, i.e. after relaxation):
///   f(v_i) = Σ_j w(|v_i − r_j|) f_j / Σ_j w(|v_i − r_j|),
/// with the MPS weight w of Kernel.h over r_e = @a effectiveRadius, the same weights as the
/// relaxation's weighted mean t_i. Integer attributes (ids, flags, material indices), whose
/// means would name nothing, take instead the value of the nearest particle within r_e (of
/// equally near ones, the first in @a particles), exactly: they are flagged
/// MeshAttribute::integer and held in MeshAttribute::integers (means as floats in
/// MeshAttribute::values). The type is the file's (readParticles()); CSV declares none, and
/// a column of whole numbers there reads as Int64: write 300.0, not 300, for a quantity to
/// be averaged. A vertex with no particle within r_e gets 0. A NaN or infinite value is
/// averaged as it is: every vertex within r_e of its particle gets NaN (or an infinity) in
/// that component (`nonbloppy mesh` warns of such vertices, `nonbloppy inspect` counts such
/// values in the particle file). Every component is interpolated independently. An attribute already on the mesh under the same name is
/// replaced (also on a mesh without vertices).
/// Cost: a ParticleIndex of the particles with cells of r_e (O(N), not interruptible); the
/// vertices grouped by cells of 1.5 r_e (a parallel radix sort); per group, its particles
/// within r_e of its vertices' box, gathered once; per vertex, the distances to those (four
/// at a time) and the kernel at the ones within r_e (about 40), parallel over groups. A
/// vertex's particles come in the order of a search of its own and its sums run in that
/// order in double, so the result does not depend on the thread count or the grouping. The
/// 64x benchmark input with the dam-break frame's id and velocity: 0.30 s for 2.4M vertices
/// (two threads), against 0.22 s for the two relaxation steps before it.
/// @param mesh         vertices to sample at; gets (or has replaced) one attribute per name
/// @param particles    positions and attributes, world units; only read
/// @param names        attribute names, as resolveAttributeNames() takes them ("all" for every one)
/// @param effectiveRadius  r_e, world units, as the relaxation's
/// @param interrupter  optional; start("interpolate attributes") … end() around the work
///                     (not for an empty mesh or no names), wasInterrupted() before each
///                     block of 256 vertices
/// @throw ParameterError for r_e ≤ 0, > 1e18 or not finite, what checkAttributes() refuses, or
///        particles ParticleIndex::build() refuses
///        (r_e below kMinCellSize, a non-finite position, coordinates too far from the
///        origin); CancelledError("interrupted during interpolate attributes") when
///        @a interrupter says so.
NONBLOPPY_API void interpolateAttributes(SurfaceMesh& mesh, const ParticleSet& particles,
                           const std::vector<std::string>& names, double effectiveRadius,
                           openvdb::util::NullInterrupter* interrupter = nullptr);

} // namespace nonbloppy

#endif // NONBLOPPY_INTERPOLATE_ATTRIBUTES_H
