// SPDX-License-Identifier: Apache-2.0
/// @file ParticleIndexImpl.h
/// @brief Private: the representation behind nonbloppy::ParticleIndex and the cell walk the
///        stages share. Only src/ includes it (it pulls in tools/PointIndexGrid.h).

#ifndef NONBLOPPY_PARTICLE_INDEX_IMPL_H
#define NONBLOPPY_PARTICLE_INDEX_IMPL_H

#include <nonbloppy/ParticleIndex.h>

#include <openvdb/tools/PointIndexGrid.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace nonbloppy {

struct ParticleIndex::Impl
{
    std::vector<openvdb::Vec3f> sortedPositions;
    std::vector<uint32_t> originalIndex;
    double cellSize = 0.0;
    openvdb::tools::PointIndexGrid::Ptr grid;  ///< indices refer to sorted slots
    /// The index-space box of the grid's leaves: every particle's cell lies inside, so
    /// queries are clipped to it (a query box far wider than the particles, e.g. a voxel
    /// hundreds of times r_e, would otherwise walk billions of empty cells).
    openvdb::CoordBBox leafBounds;
    openvdb::BBoxd bounds;  ///< the particles' world-space box (empty without particles)
};

namespace cancellation_internal { class CancelPoll; }

namespace particle_index_internal {

/// What one parallel pass over positions finds: the first non-finite one, and the box of the
/// finite positions before it.
struct PositionScan
{
    size_t firstNonFinite;  ///< index of the first non-finite position, or size() if none
    openvdb::Vec3f min{std::numeric_limits<float>::max()};     ///< per axis, over the finite ones
    openvdb::Vec3f max{-std::numeric_limits<float>::max()};    ///< (min > max when there are none)

    /// The largest |coordinate| (0 when there are no finite positions).
    float maxAbs() const
    {
        return min[0] > max[0] ? 0.0f : std::max({-min[0], -min[1], -min[2], max[0], max[1], max[2]});
    }
};

/// PositionScan of @a positions, in parallel (unspecified after a stop of @a poll, which is
/// asked every 4096 positions of a task). Cost: O(n), reads each position once.
PositionScan scanPositions(const std::vector<openvdb::Vec3f>& positions, cancellation_internal::CancelPoll& poll);

using IndexTree = openvdb::tools::PointIndexTree;
using IndexLeaf = IndexTree::LeafNodeType;

/// Throw ParameterError("particle index cells of C are too small for --radius R: at most 8
/// cells per radius (...)") or "... too large ...: at least 0.25 ..." unless
/// kMinCellsPerRadius ≤ r_e / cell ≤ kMaxCellsPerRadius. An index without particles passes:
/// its searches find nothing whatever its cells.
inline void requireCellsPerRadius(const ParticleIndex& index, double effectiveRadius)
{
    const double cellsPerRadius = effectiveRadius / index.cellSize();
    if (index.size() == 0 || (cellsPerRadius >= kMinCellsPerRadius && cellsPerRadius <= kMaxCellsPerRadius)) {
        return;
    }
    const bool small = cellsPerRadius > kMaxCellsPerRadius;
    std::ostringstream msg;
    msg << "particle index cells of " << index.cellSize() << " are too " << (small ? "small" : "large")
        << " for --radius " << effectiveRadius << ": at " << (small ? "most " : "least ")
        << (small ? kMaxCellsPerRadius : kMinCellsPerRadius)
        << " cells per radius (build the index with cells of r_e/2, " << effectiveRadius / 2.0 << ")";
    throw ParameterError(msg.str());
}

/// "non-finite position of particle N": how ParticleIndex::build() and the spacing estimate
/// (which meets the positions first when no --radius is given) refuse a NaN or infinity.
inline std::string nonFinitePositionMessage(size_t particle)
{
    return "non-finite position of particle " + std::to_string(particle);
}

/// Index-space cell holding world position @a x (cells are centred on integer coordinates,
/// as OpenVDB's PointPartitioner buckets them).
inline openvdb::Coord cellOf(const openvdb::Vec3d& x, double cellSize)
{
    return openvdb::Coord(int(std::floor(x[0] / cellSize + 0.5)),
                          int(std::floor(x[1] / cellSize + 0.5)),
                          int(std::floor(x[2] / cellSize + 0.5)));
}

/// Call visit(firstSlot, endSlot) for every non-empty run of sorted slots whose cells overlap
/// the world box [minCorner, maxCorner]. Cells along z inside one leaf hold consecutive
/// slots, so each (x, y) column of a leaf is one run. Visiting order is fixed (x, y, z
/// ascending), which keeps every sum built from the runs independent of threading.
/// Cost: one probe per (x, y) cell column and leaf of the box clipped to @a index's leaves.
template<typename AccessorT, typename VisitorT>
inline void forEachRunInBox(const ParticleIndex::Impl& index, AccessorT& accessor,
                            const openvdb::Vec3d& minCorner, const openvdb::Vec3d& maxCorner,
                            VisitorT&& visit)
{
    // Clipped in world units first: a corner too far out for an int cell number (a huge
    // query radius) must not overflow the conversion. A box beyond the bounds on some axis
    // (or a NaN corner) leaves that axis empty and returns before any conversion: clipping
    // only its far corner left the near one out of int range, and the loop then ran from
    // INT_MIN, for minutes, for a vertex 2^31 cells out (API review).
    if (index.leafBounds.empty()) return;
    const double cellSize = index.cellSize;
    const openvdb::Vec3d boundsMin = (index.leafBounds.min().asVec3d() - 0.5) * cellSize;
    const openvdb::Vec3d boundsMax = (index.leafBounds.max().asVec3d() + 0.5) * cellSize;
    const openvdb::Vec3d clippedMin = openvdb::math::maxComponent(minCorner, boundsMin);
    const openvdb::Vec3d clippedMax = openvdb::math::minComponent(maxCorner, boundsMax);
    for (int axis = 0; axis < 3; ++axis) {
        if (!(clippedMin[axis] <= clippedMax[axis])) return;
    }
    const openvdb::Coord lo = cellOf(clippedMin, cellSize);
    const openvdb::Coord hi = cellOf(clippedMax, cellSize);
    constexpr int kLeafMask = int(IndexLeaf::DIM) - 1;
    openvdb::Coord ijk;
    for (ijk[0] = lo[0]; ijk[0] <= hi[0]; ++ijk[0]) {
        for (ijk[1] = lo[1]; ijk[1] <= hi[1]; ++ijk[1]) {
            for (int z = lo[2]; z <= hi[2];) {
                const int zEnd = std::min(hi[2], (z & ~kLeafMask) + kLeafMask);
                ijk[2] = z;
                if (const IndexLeaf* leaf = accessor.probeConstLeaf(ijk)) {
                    const openvdb::Index first = IndexLeaf::coordToOffset(ijk);
                    const openvdb::Index last = first + openvdb::Index(zEnd - z);
                    const uint32_t begin = first == 0 ? 0u : uint32_t(leaf->getValue(first - 1));
                    const uint32_t end = uint32_t(leaf->getValue(last));
                    if (end > begin) {
                        const uint32_t slot = uint32_t(leaf->indices()[begin]);
                        visit(slot, slot + (end - begin));
                    }
                }
                z = zEnd + 1;
            }
        }
    }
}

} // namespace particle_index_internal
} // namespace nonbloppy

#endif // NONBLOPPY_PARTICLE_INDEX_IMPL_H
