// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/ComputeNormals.h>
#include <nonbloppy/Error.h>

#include "Cancellation.h"
#include "PolygonIndices.h"
#include "VectorArea.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <limits>
#include <memory>

namespace nonbloppy {

namespace {

/// Polygons per block: the unit in which vertex ranges find the polygons that touch them.
constexpr size_t kPolygonsPerBlock = 1024;

/// Vertices per range: each range sums its vertices' normals in a scratch array of its own,
/// 24 bytes per vertex (768 KB, which stays in a core's L2 cache).
constexpr size_t kVerticesPerRange = 32768;

/// The ranges a block touches, listed when they are this few (a block of the extraction's
/// mesh touches its region's range or two, and the earlier ones holding its seam vertices);
/// beyond, every range between its lowest and highest corner's.
constexpr uint32_t kListedRanges = 6;

/// When the blocks' ranges add up to more than this many visits per polygon (meshes whose
/// polygon order and vertex order do not follow each other, e.g. a shuffled OBJ), there is
/// one range of all vertices instead: the serial sum, every polygon visited once.
constexpr double kMaxVisitsPerPolygon = 3.0;

/// The vertex ranges that the corners of one block of polygons fall in.
struct BlockRanges
{
    std::array<uint32_t, kListedRanges> listed;  ///< ascending, the first @c count of them
    uint32_t count = 0;          ///< how many are listed, or kListedRanges + 1: all of [lowest, highest]
    uint32_t lowest = 0, highest = 0;
    uint32_t highestCorner = 0;  ///< for the range check of the corners

    size_t visits() const { return count <= kListedRanges ? count : highest - lowest + 1; }
};

} // namespace

namespace cancellation_internal {

void computeNormals(SurfaceMesh& mesh, CancelPoll& poll)
{
    const std::vector<openvdb::Vec3s>& p = mesh.points;
    const size_t vertexCount = p.size(), triangleCount = mesh.triangles.size();
    const size_t polygonCount = triangleCount + mesh.quads.size();
    const size_t blockCount = (polygonCount + kPolygonsPerBlock - 1) / kPolygonsPerBlock;
    const auto blockEnd = [&](size_t block) { return std::min(polygonCount, (block + 1) * kPolygonsPerBlock); };

    // The ranges of each block, in parallel with allocating the normals where mesh.normals
    // cannot hold them: resize() zero-fills in one thread (29 MB and 7,000 page faults for the
    // 64x benchmark mesh). A mesh that already has the room (SurfaceReconstructor's, frame
    // after frame) keeps it.
    std::vector<BlockRanges> blocks(blockCount);
    const bool haveRoom = mesh.normals.capacity() >= vertexCount;
    std::vector<openvdb::Vec3s> allocated;
    tbb::parallel_invoke(
        [&] {
            tbb::parallel_for(tbb::blocked_range<size_t>(0, blockCount),
                [&](const tbb::blocked_range<size_t>& range) {
                    for (size_t block = range.begin(); block < range.end(); ++block) {
                        if (poll.stopped()) return;
                        BlockRanges& b = blocks[block];
                        b.lowest = std::numeric_limits<uint32_t>::max();
                        uint32_t lastRange = std::numeric_limits<uint32_t>::max();  // most corners repeat it
                        for (size_t n = block * kPolygonsPerBlock; n < blockEnd(block); ++n) {
                            const auto [corners, cornerCount] = polygon_indices_internal::cornersOf(mesh, n);
                            for (int k = 0; k < cornerCount; ++k) {
                                b.highestCorner = std::max(b.highestCorner, corners[k]);
                                const uint32_t r = uint32_t(corners[k] / kVerticesPerRange);
                                if (r == lastRange) continue;
                                lastRange = r;
                                b.lowest = std::min(b.lowest, r);
                                b.highest = std::max(b.highest, r);
                                if (b.count > kListedRanges) continue;
                                uint32_t* end = b.listed.data() + b.count;
                                uint32_t* at = std::lower_bound(b.listed.data(), end, r);
                                if (at != end && *at == r) continue;
                                if (b.count == kListedRanges) {
                                    b.count = kListedRanges + 1;
                                    continue;
                                }
                                std::copy_backward(at, end, end + 1);
                                *at = r;
                                ++b.count;
                            }
                        }
                    }
                });
        },
        [&] {
            if (!haveRoom) allocated.resize(vertexCount);
        });
    poll.throwIfStopped();
    // A corner out of range: the message names the first such polygon, and mesh.normals is
    // left untouched.
    for (const BlockRanges& b : blocks) {
        if (b.highestCorner >= vertexCount) polygon_indices_internal::requireValidIndices(mesh);
    }
    if (haveRoom) mesh.normals.resize(vertexCount);
    else mesh.normals.swap(allocated);
    std::vector<openvdb::Vec3s>& normals = mesh.normals;

    // Each range's blocks, in block order.
    size_t visits = 0;
    for (const BlockRanges& b : blocks) visits += b.visits() * kPolygonsPerBlock;
    const bool oneRange = double(visits) > kMaxVisitsPerPolygon * double(polygonCount);
    const size_t verticesPerRange = oneRange ? std::max<size_t>(vertexCount, 1) : kVerticesPerRange;
    const size_t rangeCount = (vertexCount + verticesPerRange - 1) / verticesPerRange;
    std::vector<size_t> blocksBefore(rangeCount + 1, 0);  // then the start of each range's list
    std::vector<uint32_t> blocksOfRange;
    const auto forEachRange = [&](const BlockRanges& b, auto&& f) {
        if (oneRange) f(size_t(0));
        else if (b.count <= kListedRanges) for (uint32_t k = 0; k < b.count; ++k) f(size_t(b.listed[k]));
        else for (size_t r = b.lowest; r <= b.highest; ++r) f(r);
    };
    if (rangeCount > 0) {
        for (const BlockRanges& b : blocks) forEachRange(b, [&](size_t r) { ++blocksBefore[r + 1]; });
        for (size_t r = 0; r < rangeCount; ++r) blocksBefore[r + 1] += blocksBefore[r];
        blocksOfRange.resize(blocksBefore[rangeCount]);
        std::vector<size_t> next(blocksBefore.begin(), blocksBefore.end() - 1);
        for (size_t block = 0; block < blockCount; ++block) {
            forEachRange(blocks[block], [&](size_t r) { blocksOfRange[next[r]++] = uint32_t(block); });
        }
    }

    // Each range sums, in double and in polygon order (so the bits do not depend on the
    // ranges or the threads), twice the vector area of every polygon into each corner in it.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rangeCount, 1),
        [&](const tbb::blocked_range<size_t>& ranges) {
            std::unique_ptr<openvdb::Vec3d[]> sums(new openvdb::Vec3d[std::min(verticesPerRange, vertexCount)]);
            for (size_t r = ranges.begin(); r < ranges.end(); ++r) {
                const size_t first = r * verticesPerRange;
                const size_t end = std::min(vertexCount, first + verticesPerRange);
                std::fill(sums.get(), sums.get() + (end - first), openvdb::Vec3d(0.0));
                const auto inRange = [&](uint32_t corner) { return first <= corner && corner < end; };
                const auto add = [&](uint32_t corner, const openvdb::Vec3d& normal) {
                    if (inRange(corner)) sums[corner - first] += normal;
                };
                for (size_t k = blocksBefore[r]; k < blocksBefore[r + 1]; ++k) {
                    if (poll.stopped()) return;
                    const size_t block = blocksOfRange[k];
                    for (size_t n = block * kPolygonsPerBlock; n < blockEnd(block); ++n) {
                        if (n < triangleCount) {
                            const openvdb::Vec3I& t = mesh.triangles[n];
                            if (!inRange(t[0]) && !inRange(t[1]) && !inRange(t[2])) continue;
                            const openvdb::Vec3d a(p[t[0]]), b(p[t[1]]), c(p[t[2]]);
                            const openvdb::Vec3d normal = twiceVectorArea(a, b, c);
                            add(t[0], normal); add(t[1], normal); add(t[2], normal);
                        } else {
                            const openvdb::Vec4I& q = mesh.quads[n - triangleCount];
                            if (!inRange(q[0]) && !inRange(q[1]) && !inRange(q[2]) && !inRange(q[3])) continue;
                            const openvdb::Vec3d a(p[q[0]]), b(p[q[1]]), c(p[q[2]]), d(p[q[3]]);
                            const openvdb::Vec3d normal = twiceVectorArea(a, b, c, d);
                            add(q[0], normal); add(q[1], normal); add(q[2], normal); add(q[3], normal);
                        }
                    }
                }
                for (size_t i = first; i < end; ++i) {
                    if (poll.stoppedAt(i - first)) return;
                    const openvdb::Vec3d& sum = sums[i - first];
                    const double length = sum.length();
                    normals[i] = length > 0.0 ? openvdb::Vec3s(sum / length) : openvdb::Vec3s(0.0f);
                }
            }
        });
    poll.throwIfStopped();
}

} // namespace cancellation_internal

void computeNormals(SurfaceMesh& mesh, openvdb::util::NullInterrupter* interrupter)
{
    cancellation_internal::CancelPoll poll(interrupter, "compute normals");
    cancellation_internal::computeNormals(mesh, poll);
}

} // namespace nonbloppy
