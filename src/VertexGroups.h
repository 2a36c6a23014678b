// SPDX-License-Identifier: Apache-2.0
/// @file VertexGroups.h
/// @brief Private: mesh vertices grouped by the cell of a coarse lattice they fall in, so
///        that the stages which sum over a vertex's particles (relax, interpolate
///        attributes) gather one candidate list per group instead of one per vertex.

#ifndef NONBLOPPY_VERTEX_GROUPS_H
#define NONBLOPPY_VERTEX_GROUPS_H

#include "UnwrittenVector.h"

#include <openvdb/math/Vec3.h>

#include <algorithm>
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

/// Candidate particles of one group of vertices: those of a run of sorted particle slots
/// (ParticleIndex) that lie within a radius of the group's box, as separate x, y, z arrays
/// and, if @a kWithSlots, their slots, in the order gathered (so a vertex's particles among
/// them keep the order of its own search), padded to a multiple of @a kLanes with
/// particles far outside every support (weight 0). The buffers only grow: one per task.
template<size_t kLanes, bool kWithSlots>
struct GroupCandidates
{
    std::vector<float> x, y, z;
    std::vector<uint32_t> slots;  ///< only if kWithSlots
    size_t count = 0;

    void clear() { count = 0; }

    /// Append the particles of slots [first, end) that lie within @a radius of the box
    /// [boxMin, boxMax]: only they can reach a vertex inside the box. Skipping the others
    /// (the corners and edges of the grown box) halves the work of every vertex. Written
    /// without branches (store, then advance only if kept): half the particles are
    /// dropped at random, which a branch would mispredict. The distance to the box is the
    /// distance to the particle clamped into it (min and max, no branch either: the same
    /// value as the largest of 0, min - p and p - max, which GCC compiled to a branch per
    /// axis). 64x benchmark input, relax stage, 4 paired runs at one thread: 0.56-0.63 s
    /// with the branches, 0.47-0.54 s without.
    /// Inlined always, so that a caller compiled for AVX2 compiles it for AVX2 too.
    __attribute__((always_inline)) inline void gather(const std::vector<openvdb::Vec3f>& positions, uint32_t first,
        uint32_t end, const openvdb::Vec3f& boxMin, const openvdb::Vec3f& boxMax, float radius2)
    {
        reserve(count + (end - first) + kLanes);
        float* __restrict px = x.data();
        float* __restrict py = y.data();
        float* __restrict pz = z.data();
        uint32_t* __restrict ps = kWithSlots ? slots.data() : nullptr;
        // Locals, so the stores through px, py, pz cannot be taken to change them.
        const float minX = boxMin[0], minY = boxMin[1], minZ = boxMin[2];
        const float maxX = boxMax[0], maxY = boxMax[1], maxZ = boxMax[2];
        size_t n = count;
        for (uint32_t k = first; k < end; ++k) {
            const openvdb::Vec3f& p = positions[k];
            const float dx = p[0] - std::min(std::max(p[0], minX), maxX);
            const float dy = p[1] - std::min(std::max(p[1], minY), maxY);
            const float dz = p[2] - std::min(std::max(p[2], minZ), maxZ);
            const float outside2 = dx * dx + dy * dy + dz * dz;
            px[n] = p[0];
            py[n] = p[1];
            pz[n] = p[2];
            if constexpr (kWithSlots) ps[n] = k;
            n += outside2 < radius2 ? 1 : 0;
        }
        count = n;
    }

    /// Pad to a multiple of kLanes with a position at least r_e away from every vertex.
    void pad(float farAway)
    {
        reserve(count + kLanes);
        while (count % kLanes != 0) {
            x[count] = y[count] = z[count] = farAway;
            if constexpr (kWithSlots) slots[count] = 0;
            ++count;
        }
    }

private:
    void reserve(size_t size)
    {
        if (x.size() < size) {
            x.resize(2 * size);
            y.resize(2 * size);
            z.resize(2 * size);
            if constexpr (kWithSlots) slots.resize(2 * size);
        }
    }
};

} // namespace vertex_groups_internal
} // namespace nonbloppy

#endif // NONBLOPPY_VERTEX_GROUPS_H
