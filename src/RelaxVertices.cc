// SPDX-License-Identifier: Apache-2.0
#include "Cancellation.h"
#include "InstructionSet.h"
#include "ParameterChecks.h"
#include "ParticleIndexImpl.h"
#include "UnwrittenVector.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/Kernel.h>
#include <nonbloppy/RelaxVertices.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <new>
#include <utility>
#include <vector>
#include <sstream>

namespace nonbloppy {

namespace {

using cancellation_internal::CancelPoll;

// Buffers of millions of keys are filled by parallel loops, which then take their page
// faults on both threads instead of a serial memset beforehand.
using memory_internal::UnwrittenVector;

/// Candidates processed side by side (two SSE registers, or one AVX register).
constexpr size_t kLanes = 8;
/// Vertex groups of a task between two polls: each group gathers its candidate particles
/// and sums over them for every vertex, so a task of many groups runs for milliseconds.
constexpr size_t kGroupsPerPoll = 16;
/// Steps of one group between two polls: with a large t one group takes many, each of them
/// one candidate gather and one sum per vertex.
constexpr int kStepsPerPoll = 16;
/// Edge of the cells vertices are grouped by, in particle-index cells. Larger groups share one
/// gather among more vertices but give each a longer candidate list. 64x benchmark input,
/// relax stage (t = 2), groups bounded by their vertices' box, one thread / two: 2 cells
/// 0.80-0.87 / 0.54-0.61 s, 3 cells 0.61-0.65 / 0.41-0.43 s, 4 cells 0.64-0.83 / 0.34-0.39 s,
/// 5 cells 0.68-0.71 / 0.39-0.44 s.
constexpr double kGroupCells = 3.0;

/// Candidate particles of one group of vertices, as separate x, y, z arrays padded to a
/// multiple of kLanes with particles far outside every support (weight 0).
struct CandidateBuffer
{
    std::vector<float> x, y, z;
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
    void gather(const std::vector<openvdb::Vec3f>& positions, uint32_t first, uint32_t end,
                const openvdb::Vec3f& boxMin, const openvdb::Vec3f& boxMax, float radius2)
    {
        reserve(count + (end - first) + kLanes);
        float* __restrict px = x.data();
        float* __restrict py = y.data();
        float* __restrict pz = z.data();
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
        }
    }
};

/// Every relaxation step for a range of vertex groups, group after group: a vertex's step
/// depends only on its own position and the particles, so a group can take all its steps
/// before the next group starts, with its positions (and its particles) still in cache, and
/// writes them in place, as no other group reads them. Each step of a group gathers the
/// particles within r_e of its vertices' current box once, and every vertex of the group then
/// sums over that contiguous list with per-lane accumulators (vectorizable without
/// reassociating any sum, so results stay exact and independent of threads: a vertex's sum
/// order depends only on its group's list, which is the same in whichever order the groups run).
struct RelaxGroupsOp
{
    const ParticleIndex& particles;
    const UnwrittenVector<uint32_t>& vertexOrder;  ///< vertices sorted by their first cell
    const std::vector<size_t>& groupStart;      ///< groups of vertexOrder sharing that cell
    std::vector<openvdb::Vec3s>& points;        ///< read, relaxed and written back per group
    int iterations;
    float effectiveRadius;
    float blend;
    float maxStep;  ///< cap on one step's length, world units; 0: no cap (the paper)
    CancelPoll& poll;
    std::atomic<size_t>& groupsDone;  ///< for progress
    bool avx2;      ///< run the AVX2 copy of the loop (InstructionSet.h)

    void operator()(const tbb::blocked_range<size_t>& range) const
    {
        if (avx2) relaxRangeAvx2(range);
        else relaxRange(range);
        const size_t done = groupsDone.fetch_add(range.size()) + range.size();
        poll.stopped(int(100.0 * double(done) / double(groupStart.size() - 1)));
    }

    /// relaxRange() compiled for AVX2 (it is inlined here).
    NONBLOPPY_TARGET_AVX2 void relaxRangeAvx2(const tbb::blocked_range<size_t>& range) const
    {
        relaxRange(range);
    }

    /// All steps for the vertex groups of @a range. Always inlined, so that each caller
    /// compiles it for its own instruction set.
    __attribute__((always_inline)) inline void relaxRange(const tbb::blocked_range<size_t>& range) const
    {
        const auto& positions = particles.sortedPositions();
        auto accessor = particles.impl().grid->getConstAccessor();
        const double cellSize = particles.cellSize();
        const float radius = effectiveRadius;
        const float minDistance2 = (kMinDistanceFraction * radius) * (kMinDistanceFraction * radius);
        CandidateBuffer candidates;
        std::vector<openvdb::Vec3s> current, next;  // the group's positions, in group order
        for (size_t g = range.begin(); g < range.end(); ++g) {
            if ((g - range.begin()) % kGroupsPerPoll == 0 && poll.stopped()) return;
            const size_t begin = groupStart[g], end = groupStart[g + 1];
            current.resize(end - begin);
            next.resize(end - begin);
            for (size_t n = begin; n < end; ++n) current[n - begin] = points[vertexOrder[n]];
            for (int iteration = 0; iteration < iterations; ++iteration) {
                if (iteration > 0 && iteration % kStepsPerPoll == 0 && poll.stopped()) return;
                step(current, next, positions, accessor, cellSize, radius, minDistance2, candidates);
                current.swap(next);
            }
            for (size_t n = begin; n < end; ++n) points[vertexOrder[n]] = current[n - begin];
        }
    }

    /// One step of one group: @a next from @a previous (the group's positions).
    template<typename AccessorT>
    __attribute__((always_inline)) inline void step(const std::vector<openvdb::Vec3s>& previous,
        std::vector<openvdb::Vec3s>& next, const std::vector<openvdb::Vec3f>& positions, AccessorT& accessor,
        double cellSize, float radius, float minDistance2, CandidateBuffer& candidates) const
    {
        // The box of the group's vertices, grown by r_e, holds every particle near any of
        // them. Their own box rather than the cell they were grouped by: it is thinner (a
        // surface crosses the cell as a sheet), and it stays right as they move.
        openvdb::Vec3f vertexMin = previous[0], vertexMax = vertexMin;
        for (size_t n = 1; n < previous.size(); ++n) {
            vertexMin = openvdb::math::minComponent(vertexMin, previous[n]);
            vertexMax = openvdb::math::maxComponent(vertexMax, previous[n]);
        }
        // Float rounding of the distances: grow the box by a hair so the filter never
        // drops a particle that a vertex on the box's face can reach.
        const float slack = 1e-4f * float(cellSize);
        const openvdb::Vec3f boxMin = vertexMin - openvdb::Vec3f(slack);
        const openvdb::Vec3f boxMax = vertexMax + openvdb::Vec3f(slack);
        candidates.clear();
        particle_index_internal::forEachRunInBox(particles.impl(), accessor,
            openvdb::Vec3d(boxMin) - openvdb::Vec3d(radius), openvdb::Vec3d(boxMax) + openvdb::Vec3d(radius),
            [&](uint32_t first, uint32_t last) {
                candidates.gather(positions, first, last, boxMin, boxMax, radius * radius);
            });
        candidates.pad(boxMax[0] + 4.0f * radius);
        const size_t count = candidates.count;
        const float* cx = candidates.x.data();
        const float* cy = candidates.y.data();
        const float* cz = candidates.z.data();

        for (size_t n = 0; n < previous.size(); ++n) {
            const openvdb::Vec3s v = previous[n];
            // Offsets from the vertex rather than absolute positions: the mean is then
            // exact to float precision however far the fluid is from the origin.
            float sw[kLanes] = {}, sx[kLanes] = {}, sy[kLanes] = {}, sz[kLanes] = {};
            for (size_t c = 0; c < count; c += kLanes) {
                for (size_t l = 0; l < kLanes; ++l) {
                    const float dx = cx[c + l] - v[0];
                    const float dy = cy[c + l] - v[1];
                    const float dz = cz[c + l] - v[2];
                    const float d2 = dx * dx + dy * dy + dz * dz;
                    // re/d − 1 is ≤ 0 from d = r_e on: clamping at 0 cuts the support
                    // without a branch, so the loop vectorizes.
                    float w = radius / std::sqrt(std::max(d2, minDistance2)) - 1.0f;
                    w = w > 0.0f ? w : 0.0f;
                    sw[l] += w;
                    sx[l] += w * dx;
                    sy[l] += w * dy;
                    sz[l] += w * dz;
                }
            }
            float weightSum = 0.0f, mx = 0.0f, my = 0.0f, mz = 0.0f;
            for (size_t l = 0; l < kLanes; ++l) {
                weightSum += sw[l];
                mx += sx[l];
                my += sy[l];
                mz += sz[l];
            }
            if (weightSum > 0.0f) {
                const float scale = blend / weightSum;
                float dx = scale * mx, dy = scale * my, dz = scale * mz;
                const float length2 = dx * dx + dy * dy + dz * dz;
                if (maxStep > 0.0f && length2 > maxStep * maxStep) {
                    const float shrink = maxStep / std::sqrt(length2);
                    dx *= shrink;
                    dy *= shrink;
                    dz *= shrink;
                }
                next[n] = openvdb::Vec3s(v[0] + dx, v[1] + dy, v[2] + dz);
            } else {
                next[n] = v;  // no particle within r_e: stays put
            }
        }
    }
};

/// Stable LSD radix sort of @a values by their bits [@a low, @a low + @a bits), 11 bits a
/// pass, through @a spare. The values are cut into a fixed number of chunks (not one per
/// thread): each pass counts the digits of every chunk in parallel, takes the starts in
/// digit order then chunk order, and lets every chunk place its values in order, so the
/// result is the same for any thread count. On a stop of @a poll the order is unspecified.
void radixSortHigh(UnwrittenVector<uint64_t>& values, UnwrittenVector<uint64_t>& spare, int low, int bits,
                   CancelPoll& poll)
{
    constexpr int kDigitBits = 11;
    constexpr size_t kDigits = size_t(1) << kDigitBits;
    constexpr size_t kChunks = 16;
    const size_t count = values.size();
    const size_t chunkSize = (count + kChunks - 1) / kChunks;
    spare.resize(count);
    std::vector<size_t> next(kChunks * kDigits);
    for (int shift = low; shift < low + bits; shift += kDigitBits) {
        const auto digitOf = [&](uint64_t v) { return size_t(v >> shift) & (kDigits - 1); };
        tbb::parallel_for(tbb::blocked_range<size_t>(0, kChunks, 1), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t chunk = r.begin(); chunk < r.end(); ++chunk) {
                size_t* counts = next.data() + chunk * kDigits;
                std::fill(counts, counts + kDigits, size_t(0));
                const size_t begin = chunk * chunkSize, end = std::min(begin + chunkSize, count);
                for (size_t i = begin; i < end; ++i) {
                    if (poll.stoppedAt(i - begin)) return;
                    ++counts[digitOf(values[i])];
                }
            }
        });
        if (poll.stopped()) return;
        size_t start = 0;
        for (size_t digit = 0; digit < kDigits; ++digit) {
            for (size_t chunk = 0; chunk < kChunks; ++chunk) {
                size_t& slot = next[chunk * kDigits + digit];
                const size_t inChunk = slot;
                slot = start;
                start += inChunk;
            }
        }
        tbb::parallel_for(tbb::blocked_range<size_t>(0, kChunks, 1), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t chunk = r.begin(); chunk < r.end(); ++chunk) {
                size_t* slots = next.data() + chunk * kDigits;
                const size_t begin = chunk * chunkSize, end = std::min(begin + chunkSize, count);
                for (size_t i = begin; i < end; ++i) spare[slots[digitOf(values[i])]++] = values[i];
            }
        });
        values.swap(spare);
    }
}

/// @a order[n] = vertexAt(n), and the start of every run of equal keyAt(n) (plus the end) in
/// @a groupStart, for n < @a count sorted by key: a count of starts per block, its prefix
/// sum, then each block writes its own.
template<typename KeyAt, typename VertexAt>
void writeGroups(size_t count, const KeyAt& keyAt, const VertexAt& vertexAt, UnwrittenVector<uint32_t>& order,
                 std::vector<size_t>& groupStart, CancelPoll& poll)
{
    order.resize(count);
    constexpr size_t kBlock = 16384;
    const size_t blocks = (count + kBlock - 1) / kBlock;
    std::vector<size_t> startsBefore(blocks + 1, 0);
    const auto startsGroup = [&](size_t n) { return n == 0 || keyAt(n) != keyAt(n - 1); };
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t b = r.begin(); b < r.end(); ++b) {
            if (poll.stopped()) return;
            size_t starts = 0;
            for (size_t n = b * kBlock, end = std::min(n + kBlock, count); n < end; ++n) {
                order[n] = vertexAt(n);
                starts += startsGroup(n);
            }
            startsBefore[b + 1] = starts;
        }
    });
    poll.throwIfStopped();
    for (size_t b = 0; b < blocks; ++b) startsBefore[b + 1] += startsBefore[b];
    groupStart.resize(startsBefore[blocks] + 1);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t b = r.begin(); b < r.end(); ++b) {
            size_t out = startsBefore[b];
            for (size_t n = b * kBlock, end = std::min(n + kBlock, count); n < end; ++n) {
                if (startsGroup(n)) groupStart[out++] = n;
            }
        }
    });
    groupStart.back() = count;
}

/// Sort the vertex numbers by the group cell (edge @a groupSize) their position falls in and
/// return the start of each run of equal cells (plus the end). Cells are keyed relative to
/// the smallest cell, so the sort compares integers, not coordinates through an index; ties
/// keep vertex order, so grouping is deterministic. Every pass is parallel, and the key
/// buffers are filled without a serial memset first (UnwrittenVector): on millions of
/// vertices, serial passes left the second thread idle. When the cells of the vertices' box
/// number fewer than 2^32 (always, but for scattered vertices), the key is the cell's rank in
/// that box and the vertex number packed into 64 bits, sorted by a stable radix sort on the
/// rank's bits (two passes where a surface crosses a million cells; the comparison sort cost
/// a tenth of the step).
///
/// A vertex with a coordinate that is NaN, infinite or beyond 2^30 group cells from the
/// origin is in no group: no particle can be within r_e of it (the particle index holds
/// cells of int coordinates, a third of a group cell each), so it stays put, as a vertex
/// with no particle in reach does. Its cell would not fit an int either.
/// Asks @a poll as it goes and throws its CancelledError on a stop (the sort is stopped
/// through runStoppable()).
void groupVerticesByCell(const std::vector<openvdb::Vec3s>& points, double groupSize,
                         UnwrittenVector<uint32_t>& order, std::vector<size_t>& groupStart, CancelPoll& poll)
{
    using particle_index_internal::cellOf;
    // Largest |coordinate| of a grouped vertex; NaN fails the comparison too.
    const float reach = float(double(1 << 30) * groupSize);
    const auto inReach = [reach](const openvdb::Vec3s& p) {
        return (std::abs(p[0]) < reach) & (std::abs(p[1]) < reach) & (std::abs(p[2]) < reach);
    };
    // The cells of the lowest and highest corners of the grouped vertices' box bound every
    // one of their cells, since cellOf() is monotonic in each coordinate: min and max (which
    // vectorize) instead of a cellOf() per vertex, twice as fast. A vertex out of reach (never
    // in a mesh from extractSurface) makes a second pass that leaves it out.
    struct Box
    {
        openvdb::Vec3s lo, hi;
        size_t outOfReach;
    };
    const float inf = std::numeric_limits<float>::infinity();
    const auto boxOf = [&](bool skipOutOfReach) {
        return tbb::parallel_reduce(tbb::blocked_range<size_t>(0, points.size()),
            Box{openvdb::Vec3s(inf), openvdb::Vec3s(-inf), 0},
            [&](const tbb::blocked_range<size_t>& r, Box b) {
                if (poll.stopped()) return b;
                size_t outOfReach = 0;
                for (size_t i = r.begin(); i < r.end(); ++i) {
                    const openvdb::Vec3s& p = points[i];
                    const bool in = inReach(p);
                    outOfReach += !in;
                    if (skipOutOfReach && !in) continue;
                    b.lo = openvdb::math::minComponent(b.lo, p);
                    b.hi = openvdb::math::maxComponent(b.hi, p);
                }
                b.outOfReach += outOfReach;
                return b;
            },
            [](const Box& a, const Box& b) {
                return Box{openvdb::math::minComponent(a.lo, b.lo), openvdb::math::maxComponent(a.hi, b.hi),
                           a.outOfReach + b.outOfReach};
            });
    };
    Box box = boxOf(false);
    poll.throwIfStopped();
    if (box.outOfReach > 0) box = boxOf(true);
    poll.throwIfStopped();
    const size_t grouped = points.size() - box.outOfReach;
    if (grouped == 0) {
        order.clear();
        groupStart.assign(1, 0);
        return;
    }
    const openvdb::Coord lowest = cellOf(box.lo, groupSize), highest = cellOf(box.hi, groupSize);
    // Extents in 64 bits: a box of cells from -2^30 to 2^30 overflows a Coord.
    const uint64_t dims[3] = {uint64_t(int64_t(highest[0]) - lowest[0] + 1), uint64_t(int64_t(highest[1]) - lowest[1] + 1),
                              uint64_t(int64_t(highest[2]) - lowest[2] + 1)};
    const double cellCount = double(dims[0]) * double(dims[1]) * double(dims[2]);
    // Vertices out of reach get a key past every cell's, so the sort puts them last, where
    // they are cut off.
    if (cellCount < double(uint64_t(1) << 32)) {
        const uint64_t pastLastCell = uint64_t(cellCount);
        UnwrittenVector<uint64_t> packed(points.size()), spare;  // cell rank and vertex
        tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size()), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i < r.end(); ++i) {
                if (poll.stoppedAt(i - r.begin())) return;
                uint64_t rank = pastLastCell;
                if (inReach(points[i])) {
                    const openvdb::Coord c = cellOf(points[i], groupSize) - lowest;
                    rank = (uint64_t(c[0]) * dims[1] + uint64_t(c[1])) * dims[2] + uint64_t(c[2]);
                }
                packed[i] = (rank << 32) | uint64_t(i);
            }
        });
        poll.throwIfStopped();
        int bits = 0;
        while (bits < 32 && (uint64_t(1) << bits) <= pastLastCell) ++bits;
        radixSortHigh(packed, spare, 32, bits, poll);
        poll.throwIfStopped();
        writeGroups(grouped, [&](size_t n) { return packed[n] >> 32; },
                    [&](size_t n) { return uint32_t(packed[n]); }, order, groupStart, poll);
        return;
    }
    // Scattered vertices (a particle flung 10^5 r_e away from the rest): the cell's offsets
    // from the lowest, 32 bits per axis, compared lexicographically. (A key of 21 bits per
    // axis refused such frames after their density and surface were done.) Offsets stay
    // below 2^31, so all ones marks a vertex out of reach.
    using CellKey = std::array<uint32_t, 3>;
    constexpr uint32_t kOutOfReach = std::numeric_limits<uint32_t>::max();
    std::vector<std::pair<CellKey, uint32_t>> keyed(points.size());  // cell key and vertex
    tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size()), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            if (poll.stoppedAt(i - r.begin())) return;
            CellKey key = {kOutOfReach, kOutOfReach, kOutOfReach};
            if (inReach(points[i])) {
                const openvdb::Coord c = cellOf(points[i], groupSize);
                key = {uint32_t(int64_t(c[0]) - lowest[0]), uint32_t(int64_t(c[1]) - lowest[1]),
                       uint32_t(int64_t(c[2]) - lowest[2])};
            }
            keyed[i] = {key, uint32_t(i)};
        }
    });
    poll.throwIfStopped();
    // Keys are unique (they hold the vertex number), so any sort gives the same order.
    cancellation_internal::runStoppable(poll, [&] { tbb::parallel_sort(keyed.begin(), keyed.end()); });
    poll.throwIfStopped();
    writeGroups(grouped, [&](size_t n) { return keyed[n].first; }, [&](size_t n) { return keyed[n].second; },
                order, groupStart, poll);
}

} // namespace

void relaxVertices(SurfaceMesh& mesh, const ParticleIndex& particles, const RelaxSettings& settings,
                   openvdb::util::NullInterrupter* interrupter)
{
    instruction_set_internal::relaxVertices(mesh, particles, settings, interrupter,
                                            instruction_set_internal::InstructionSet::Auto);
}

void instruction_set_internal::relaxVertices(SurfaceMesh& mesh, const ParticleIndex& particles,
                                             const RelaxSettings& settings,
                                             openvdb::util::NullInterrupter* interrupter,
                                             InstructionSet set)
{
    std::ostringstream msg;
    parameter_checks_internal::requirePositive(settings.effectiveRadius, "--radius");
    parameter_checks_internal::requireRadiusBelowMaximum(settings.effectiveRadius);
    parameter_checks_internal::requireUnitInterval(settings.blend, "--blend");
    if (settings.iterations < 0) {
        msg << "--iterations must be >= 0, got " << settings.iterations;
        throw ParameterError(msg.str());
    }
    const double maxStep = parameter_checks_internal::stepCap(settings.maxStep);
    particle_index_internal::requireCellsPerRadius(particles, settings.effectiveRadius);
    if (settings.iterations == 0 || settings.blend == 0.0 || mesh.points.empty()) return;

    const cancellation_internal::AnnouncedStage announced(interrupter, "relax vertices");
    CancelPoll poll(interrupter, "relax vertices");
    const bool avx2 = instruction_set_internal::useAvx2(set);
    UnwrittenVector<uint32_t> order;
    std::vector<size_t> groupStart;
    // Grouped once: each step bounds a group by its vertices' current box, so its candidate
    // lists stay exact however the vertices move, and as a step moves a vertex less than r_e
    // (towards its particles) the groups stay compact.
    groupVerticesByCell(mesh.points, kGroupCells * particles.cellSize(), order, groupStart, poll);
    std::atomic<size_t> groupsDone{0};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, groupStart.size() - 1, 64),
        RelaxGroupsOp{particles, order, groupStart, mesh.points, settings.iterations,
                      float(settings.effectiveRadius), float(settings.blend), float(maxStep), poll,
                      groupsDone, avx2});
    poll.throwIfStopped();
}

} // namespace nonbloppy
