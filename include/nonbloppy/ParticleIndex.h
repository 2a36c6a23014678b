// SPDX-License-Identifier: Apache-2.0
/// @file ParticleIndex.h
/// @brief Stage "index particles": one openvdb::tools::PointIndexGrid per frame, shared by
///        density rasterization and vertex relaxation.
///
/// The index keeps its own copy of the positions as float, reordered so that the particles
/// of each index cell are contiguous. Inner loops then stream through memory instead of
/// jumping through an index array, and the PointIndexGrid's index lists (rewritten to refer
/// to the sorted order) always hold runs of consecutive numbers.

#ifndef NONBLOPPY_PARTICLE_INDEX_H
#define NONBLOPPY_PARTICLE_INDEX_H

#include <nonbloppy/Export.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/Particles.h>

#include <openvdb/openvdb.h>
#include <openvdb/util/NullInterrupter.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace nonbloppy {

/// Smallest index cell and density voxel, world units: OpenVDB's linear transforms refuse a
/// scale whose cube is below 3e-15 ("Non-zero scale values required"). Positions in metres
/// of particles spaced a micrometre apart need a smaller unit (millimetres) to be meshed.
constexpr double kMinCellSize = 1.5e-5;

/// The fewest cells per effective radius (r_e / cell size) that rasterizeDensity() and
/// relaxVertices() accept from the index they search (the most: kMaxCellsPerRadius);
/// buildSurface() uses 2. Measured on the dam-break frame against 2 cells per radius:
/// relaxation is 14× slower at 8 cells per radius, 130× at 16 and 4500× at 64 (a search
/// box probes (2·r_e/cell)² cell columns), and 22× slower at 1/4 (each cell holds
/// (cell/s)³ particles); outside these bounds a mistaken unit made an uncancellable run of
/// minutes.
constexpr double kMinCellsPerRadius = 0.25;
/// The most cells per effective radius; see kMinCellsPerRadius.
constexpr double kMaxCellsPerRadius = 8.0;

/// Particles bucketed into cubic cells of a PointIndexGrid.
/// Memory: 16 bytes per particle (float position + uint32 original index) plus the grid.
/// Thread-safe for concurrent reading once built.
class NONBLOPPY_API ParticleIndex
{
public:
    using PosType = openvdb::Vec3R;  ///< position type of the PointArray concept

    /// An empty index: no particles, an empty grid of unit cells, as build() of no
    /// particles gives (rasterizeDensity() makes an empty grid of it, relaxVertices() leaves
    /// the vertices where they are); assign the result of build() to it.
    ParticleIndex();
    ~ParticleIndex();
    /// Move: the source is left empty-handed and must only be assigned to or destroyed.
    ParticleIndex(ParticleIndex&&) noexcept;
    /// Move assignment; see the move constructor.
    ParticleIndex& operator=(ParticleIndex&&) noexcept;

    /// Bucket @a positions (world units, taken over and reordered) into cells of
    /// @a cellSize world units. Cost: O(N) time (parallel radix partitioning by OpenVDB),
    /// plus a sort of each cell's few particles by position.
    /// @param positions    world units; taken over (reordered into the index's own array)
    /// @param cellSize     cell edge, world units, ≥ kMinCellSize
    /// @param interrupter  optional; asked every 4096 particles of the checks and once per
    ///                     index leaf while slots are assigned, not during OpenVDB's
    ///                     partitioning (createPointIndexGrid takes no interrupter, and
    ///                     stopping its TBB context would leave its serial steps working on
    ///                     partial counts); no start()/end() (buildSurface() announces
    ///                     "index particles")
    /// Thread-safety: reentrant.
    /// @throw ParameterError if cellSize is not finite or below kMinCellSize, a position is
    ///        not finite, a coordinate's cell number would not fit 32 bits ("particle
    ///        coordinates up to X are too far from the origin for a cell size of C (32-bit
    ///        index space)") or there are more than 2³² − 1 particles;
    ///        CancelledError("interrupted during index particles") when @a interrupter says stop.
    static ParticleIndex build(std::vector<openvdb::Vec3f> positions, double cellSize,
                               openvdb::util::NullInterrupter* interrupter = nullptr);

    /// Number of particles.
    size_t size() const;
    /// Position of the particle at sorted slot @a k (PointArray concept, for OpenVDB tools).
    void getPos(size_t k, openvdb::Vec3R& xyz) const { xyz = sortedPositions()[k]; }
    /// Positions in cell order (world units): cells in tree order, and within a cell by
    /// position (x, then y, then z; equal positions by original index), so the order, and
    /// every sum the stages make in it, does not depend on the order the particles came in.
    const std::vector<openvdb::Vec3f>& sortedPositions() const;
    /// originalIndex()[k] is the index, in the caller's particle list, of sorted slot k.
    const std::vector<uint32_t>& originalIndex() const;
    /// Cell edge length in world units.
    double cellSize() const;
    /// The smallest box holding every particle, world units; empty (min > max) without
    /// particles. Found by build()'s check of the positions, at no extra cost.
    openvdb::BBoxd bounds() const;
    /// The tools::PointIndexGrid (as GridBase, so this header stays light; cast it with
    /// openvdb::gridPtrCast<openvdb::tools::PointIndexGrid>). Its indices refer to sorted slots.
    openvdb::GridBase::ConstPtr indexGrid() const;

    /// Internal representation (src/ParticleIndexImpl.h); the stages iterate it directly.
    struct Impl;
    /// The internal representation; only nonbloppy's own sources can use it.
    const Impl& impl() const { return *mImpl; }

private:
    std::unique_ptr<Impl> mImpl;
};

/// Build a ParticleIndex from any ParticleList (see Particles.h). The caller's array is
/// only read, through getPos(), in parallel. Cost, interrupter and thread-safety as
/// ParticleIndex::build().
/// @throw ParameterError if a position is NaN or infinite (naming the particle);
///        CancelledError when @a interrupter says stop.
template<typename ParticleListT>
ParticleIndex buildParticleIndex(const ParticleListT& particles, double cellSize,
                                 openvdb::util::NullInterrupter* interrupter = nullptr)
{
    std::vector<openvdb::Vec3f> positions(particles.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, positions.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            openvdb::Vec3R xyz;
            for (size_t n = range.begin(); n < range.end(); ++n) {
                particles.getPos(n, xyz);
                positions[n] = openvdb::Vec3f(xyz);
            }
        });
    return ParticleIndex::build(std::move(positions), cellSize, interrupter);
}

} // namespace nonbloppy

#endif // NONBLOPPY_PARTICLE_INDEX_H
