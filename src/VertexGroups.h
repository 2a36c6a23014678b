// SPDX-License-Identifier: Apache-2.0
/// @file VertexGroups.h
/// @brief Private: mesh vertices grouped by the cell of a coarse lattice they fall in, so
///        that the stages which sum over a vertex's particles (relax, interpolate
///        attributes) gather one candidate list per group instead of one per vertex.

#ifndef NONBLOPPY_VERTEX_GROUPS_H
#define NONBLOPPY_VERTEX_GROUPS_H

#include "UnwrittenVector.h"

#include <openvdb/math/Vec3.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace nonbloppy {

namespace cancellation_internal { class CancelPoll; }

namespace vertex_groups_internal {

/// Sort the vertex numbers of @a points by the group cell (edge @a groupSize, world units)
/// their position falls in: @a order lists them group after group, and @a groupStart holds
/// the start of each group in @a order, plus the end. Deterministic: groups come in cell
/// order and a group's vertices in vertex order, whatever the thread count.
///
/// A vertex with a coordinate that is NaN, infinite or beyond 2^30 group cells from the
/// origin is in no group (it is left out of @a order). Callers search a ParticleIndex whose
/// cells are no larger than @a groupSize: its particles lie within 10^9 of its cells of the
/// origin (kMaxIndexCoordinate), so no particle is within r_e of such a vertex, which keeps
/// its value as a vertex with no particle in reach does. Its cell would not fit an int either.
///
/// Cost: O(N), every pass parallel: a reduction for the vertices' box, then a stable radix
/// sort of 64-bit keys (cell rank and vertex number) on the rank's bits, two passes where a
/// surface crosses a million cells; a comparison sort only for vertices scattered over more
/// than 2^32 cells.
/// Asks @a poll as it goes and throws its CancelledError on a stop.
void groupVerticesByCell(const std::vector<openvdb::Vec3s>& points, double groupSize,
                         memory_internal::UnwrittenVector<uint32_t>& order, std::vector<size_t>& groupStart,
                         cancellation_internal::CancelPoll& poll);

} // namespace vertex_groups_internal
} // namespace nonbloppy

#endif // NONBLOPPY_VERTEX_GROUPS_H
