// SPDX-License-Identifier: Apache-2.0
/// @file VertexGroups.cc
/// @brief Private: vertices grouped by cell (VertexGroups.h), for the relaxation and the
///        attribute interpolation.

#include "VertexGroups.h"

#include "Cancellation.h"
#include "ParticleIndexImpl.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace nonbloppy {
namespace vertex_groups_internal {

namespace {

using cancellation_internal::CancelPoll;
// Buffers of millions of keys are filled by parallel loops, which then take their page
// faults on both threads instead of a serial memset beforehand.
using memory_internal::UnwrittenVector;

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

} // namespace

// Cells are keyed relative to the smallest cell, so the sort compares integers, not
// coordinates through an index; ties keep vertex order, so grouping is deterministic. Every
// pass is parallel, and the key buffers are filled without a serial memset first
// (UnwrittenVector): on millions of vertices, serial passes left the second thread idle.
// When the cells of the vertices' box number fewer than 2^32 (always, but for scattered
// vertices), the key is the cell's rank in that box and the vertex number packed into 64
// bits, sorted by a stable radix sort on the rank's bits (the comparison sort cost a tenth
// of a relaxation step).
void groupVerticesByCell(const std::vector<openvdb::Vec3s>& points, double groupSize,
                         UnwrittenVector<uint32_t>& order, std::vector<size_t>& groupStart, CancelPoll& poll)
{
    using particle_index_internal::cellOf;
    // Largest |coordinate| of a grouped vertex; NaN fails the comparison too.
    const float reach = float(double(1 << 30) * groupSize);
    // One '&' of the three tests rather than '&&', which would branch and not vectorize.
    const auto inReach = [reach](const openvdb::Vec3s& p) {
        return bool(int(std::abs(p[0]) < reach) & int(std::abs(p[1]) < reach) & int(std::abs(p[2]) < reach));
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

} // namespace vertex_groups_internal
} // namespace nonbloppy
