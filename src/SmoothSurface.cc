// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/SmoothSurface.h>

#include <nonbloppy/Error.h>

#include "Cancellation.h"
#include "ExpNonPositive.h"
#include "InstructionSet.h"
#include "MachineMemory.h"
#include "PolygonIndices.h"
#include "SurfaceStages.h"
#include "UnwrittenVector.h"
#include "VectorArea.h"

#include <tbb/parallel_for.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace nonbloppy {

namespace {

using cancellation_internal::CancelPoll;
using openvdb::Vec3d;
using openvdb::Vec3I;
using openvdb::Vec3s;
/// Per-polygon and per-entry arrays that a parallel loop fills: resized without a serial
/// memset, so their pages are first touched by all threads (UnwrittenVector.h).
using memory_internal::UnwrittenVector;

/// @throw ParameterError("smoothing the surface (N polygons) would take another 176 MB, more
///        than the 100 MB this process can still take: give --no-smooth to skip it") if
///        @a bytes more do not fit in what the process can still allocate (requireHeadroom():
///        the machine, ulimit -v and -d, the memory cgroup). The
///        smoothing's scratch is larger than the density grid's on the same particles (on
///        the 64x benchmark input 552 MiB peak against 314 without it), so the density's
///        check before rasterizing does not cover it; past a batch scheduler's limit the
///        kernel ends the process without a word.
void requireMemoryForSmoothing(double bytes, size_t polygonCount)
{
    machine_memory_internal::requireHeadroom(bytes, [&] {
        return std::make_pair("smoothing the surface (" + std::to_string(polygonCount) + " polygons) would take another "
                                  + machine_memory_internal::formatBytes(bytes),
                              std::string("give --no-smooth to skip it"));
    });
}

/// One polygon's corners: three for a triangle, four for a quad.
struct Corners
{
    uint32_t vertex[4];
    int count;
};

/// The mesh's polygons, triangles first, then quads.
struct Polygons
{
    const SurfaceMesh& mesh;
    size_t size() const { return mesh.triangles.size() + mesh.quads.size(); }
    Corners operator[](size_t n) const
    {
        const auto [corners, count] = polygon_indices_internal::cornersOf(mesh, n);
        return Corners{{corners[0], corners[1], corners[2], count == 4 ? corners[3] : 0}, count};
    }
};

/// Polygons around each vertex, in ascending order: vertex v's are
/// polygonOf[start[v] .. start[v + 1]).
struct VertexPolygons
{
    std::vector<uint64_t> start;
    std::vector<uint32_t> polygonOf;
};

VertexPolygons vertexPolygons(const Polygons& polygons, size_t vertexCount, CancelPoll& poll)
{
    VertexPolygons out;
    out.start.assign(vertexCount + 1, 0);
    for (size_t n = 0; n < polygons.size(); ++n) {
        if (poll.stoppedAt(n)) poll.throwIfStopped();
        const Corners t = polygons[n];
        for (int k = 0; k < t.count; ++k) ++out.start[t.vertex[k] + 1];
    }
    for (size_t v = 0; v < vertexCount; ++v) out.start[v + 1] += out.start[v];
    out.polygonOf.resize(out.start.back());
    std::vector<uint64_t> fill(out.start.begin(), out.start.end() - 1);
    for (size_t n = 0; n < polygons.size(); ++n) {
        if (poll.stoppedAt(n)) poll.throwIfStopped();
        const Corners t = polygons[n];
        for (int k = 0; k < t.count; ++k) out.polygonOf[fill[t.vertex[k]]++] = uint32_t(n);
    }
    return out;
}

/// Merges the polygon lists of a polygon's corners (each ascending, VertexPolygons) into one
/// ascending list, pairwise with std::merge: linear in the lists' length, where appending
/// them and sorting the whole was not. On the 64x benchmark input with --spacing, two
/// threads, polygonNeighbours()' counting pass took 0.135 → 0.107 s and its filling pass
/// 0.164 → 0.137 s. (A branch-free merge loop was slower than std::merge: 0.133 s.)
/// Holds its scratch, so that a task reuses it. Not thread-safe: one per task.
class CornerListMerger
{
public:
    /// Merge @a polygon's corner lists; @a merged points at the result (valid until the next
    /// call); returns its length.
    size_t merge(const Corners& polygon, const VertexPolygons& around, const uint32_t*& merged)
    {
        const auto listOf = [&](int k) {
            const uint32_t* base = around.polygonOf.data();
            return std::make_pair(base + around.start[polygon.vertex[k]], base + around.start[polygon.vertex[k] + 1]);
        };
        const auto [a0, a1] = listOf(0);
        const auto [b0, b1] = listOf(1);
        const auto [c0, c1] = listOf(2);
        mFirst.resize(size_t(a1 - a0) + size_t(b1 - b0));
        std::merge(a0, a1, b0, b1, mFirst.begin());
        if (polygon.count == 3) {
            mResult.resize(mFirst.size() + size_t(c1 - c0));
            std::merge(mFirst.begin(), mFirst.end(), c0, c1, mResult.begin());
        } else {
            const auto [d0, d1] = listOf(3);
            mSecond.resize(size_t(c1 - c0) + size_t(d1 - d0));
            std::merge(c0, c1, d0, d1, mSecond.begin());
            mResult.resize(mFirst.size() + mSecond.size());
            std::merge(mFirst.begin(), mFirst.end(), mSecond.begin(), mSecond.end(), mResult.begin());
        }
        merged = mResult.data();
        return mResult.size();
    }

private:
    std::vector<uint32_t> mFirst, mSecond, mResult;
};

/// Lists of polygon numbers, one per item (a polygon's neighbours, a vertex's polygons),
/// stored for the rounds' vector lanes: the items of group g (from g · lanes, one per lane)
/// have their k-th entries side by side, in entry groupStart[g] + k · lanes + lane, for k up
/// to the group's longest list; a shorter list's entries past its count are padding (a real
/// polygon), which no round adds. A vector copy then loads a step's entries with one
/// contiguous load instead of a gather. With one lane this is a plain list per item.
struct LaneLists
{
    size_t lanes = 1;
    std::vector<uint32_t> count;       ///< entries of each item (padded to whole groups with zeros)
    std::vector<uint64_t> groupStart;  ///< per group, and the total at the end
    UnwrittenVector<uint32_t> polygon;

    /// Entry of item @a n's @a k-th polygon.
    uint64_t entry(size_t n, uint32_t k) const { return groupStart[n / lanes] + uint64_t(k) * lanes + n % lanes; }

    /// groupStart from count: each group as long as its longest list.
    void startGroups()
    {
        const size_t groupCount = count.size() / lanes;
        groupStart.assign(groupCount + 1, 0);
        for (size_t g = 0; g < groupCount; ++g) {
            const uint32_t* counts = count.data() + g * lanes;
            groupStart[g + 1] = groupStart[g] + uint64_t(*std::max_element(counts, counts + lanes)) * lanes;
        }
    }
};

/// For each polygon i, every polygon j sharing a vertex with it (i itself included), once,
/// in ascending order (LaneLists, padded with the polygon itself), with the part of the
/// normal filter's weight that stays the same from round to round, in the same entries:
/// area_j · (number of vertices shared) · exp(−|c_i − c_j|²/2σ_c²), 0 for padding.
struct PolygonNeighbours : LaneLists
{
    UnwrittenVector<float> weight;
};

PolygonNeighbours polygonNeighbours(const Polygons& polygons, const VertexPolygons& around,
                                    const UnwrittenVector<Vec3s>& centroid, const UnwrittenVector<float>& area,
                                    float spatialScale, size_t lanes, CancelPoll& poll)
{
    const size_t polygonCount = polygons.size();
    const size_t groupCount = (polygonCount + lanes - 1) / lanes;
    // The polygons around i's corners, merged in ascending order: a polygon sharing k
    // vertices with i appears k times in a row. Calls @a visit(j, k) for each.
    auto forEachNeighbour = [&](size_t i, CornerListMerger& merger, auto&& visit) {
        const uint32_t* merged = nullptr;
        const size_t size = merger.merge(polygons[i], around, merged);
        for (size_t a = 0; a < size;) {
            size_t b = a + 1;
            while (b < size && merged[b] == merged[a]) ++b;
            visit(merged[a], float(b - a));
            a = b;
        }
    };
    PolygonNeighbours out;
    out.lanes = lanes;
    out.count.assign(groupCount * lanes, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, polygonCount),
        [&](const tbb::blocked_range<size_t>& range) {
            CornerListMerger merger;
            for (size_t i = range.begin(); i < range.end(); ++i) {
                if (poll.stoppedAt(i - range.begin())) return;
                uint32_t count = 0;
                forEachNeighbour(i, merger, [&](uint32_t, float) { ++count; });
                out.count[i] = count;
            }
        });
    poll.throwIfStopped();
    out.startGroups();
    requireMemoryForSmoothing(double(out.groupStart.back()) * double(sizeof(uint32_t) + sizeof(float)), polygonCount);
    out.polygon.resize(out.groupStart.back());
    out.weight.resize(out.groupStart.back());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, groupCount),
        [&](const tbb::blocked_range<size_t>& range) {
            CornerListMerger merger;
            for (size_t g = range.begin(); g < range.end(); ++g) {
                if (poll.stoppedAt((g - range.begin()) * lanes)) return;
                const uint64_t longest = (out.groupStart[g + 1] - out.groupStart[g]) / lanes;
                for (size_t i = g * lanes; i < (g + 1) * lanes; ++i) {
                    uint64_t k = 0;
                    if (i < polygonCount) {
                        forEachNeighbour(i, merger, [&](uint32_t j, float shared) {
                            const uint64_t e = out.entry(i, uint32_t(k++));
                            out.polygon[e] = j;
                            out.weight[e] = area[j] * shared * std::exp(-spatialScale * (centroid[j] - centroid[i]).lengthSqr());
                        });
                    }
                    for (; k < longest; ++k) {
                        const uint64_t e = out.entry(i, uint32_t(k));
                        out.polygon[e] = uint32_t(std::min(i, polygonCount - 1));
                        out.weight[e] = 0.0f;
                    }
                }
            }
        });
    poll.throwIfStopped();
    return out;
}

/// The polygons around each vertex, VertexPolygons' lists in the same order as LaneLists
/// (padded with polygon 0).
LaneLists vertexLanes(const VertexPolygons& around, size_t lanes, size_t polygonCount, CancelPoll& poll)
{
    const size_t vertexCount = around.start.size() - 1;
    const size_t groupCount = (vertexCount + lanes - 1) / lanes;
    LaneLists out;
    out.lanes = lanes;
    out.count.assign(groupCount * lanes, 0);
    for (size_t v = 0; v < vertexCount; ++v) out.count[v] = uint32_t(around.start[v + 1] - around.start[v]);
    out.startGroups();
    requireMemoryForSmoothing(double(out.groupStart.back()) * double(sizeof(uint32_t)), polygonCount);
    out.polygon.resize(out.groupStart.back());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, groupCount), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t g = range.begin(); g < range.end(); ++g) {
            if (poll.stoppedAt((g - range.begin()) * lanes)) return;
            const uint64_t longest = (out.groupStart[g + 1] - out.groupStart[g]) / lanes;
            for (size_t v = g * lanes; v < (g + 1) * lanes; ++v) {
                for (uint32_t k = 0; k < longest; ++k) {
                    out.polygon[out.entry(v, k)] = k < out.count[v] ? around.polygonOf[around.start[v] + k] : 0;
                }
            }
        }
    });
    poll.throwIfStopped();
    return out;
}

/// The mean of @a t's corners.
inline Vec3s centroidOf(const Corners& t, const std::vector<Vec3s>& points)
{
    const Vec3s a = points[t.vertex[0]], b = points[t.vertex[1]], c = points[t.vertex[2]];
    return t.count == 4 ? (a + b + c + points[t.vertex[3]]) * 0.25f : (a + b + c) * (1.0f / 3.0f);
}

/// centroidOf() of the polygons in @a range (triangles first, then quads), into @a out(n).
/// With SSE2 a point's x, y and z are added in three lanes at once (16-byte loads, so a
/// polygon naming the last point, whose load would pass the array's end, takes the plain
/// code): the same operations in the same order, so the same bits. The vertex rounds' pass
/// over the 64x benchmark input's surface this way: smoothSurface() 2.12–2.17 → 1.99–2.05 s
/// (two threads, AMD Zen 4, three alternating pairs).
template<typename OutT>
void centroidsOf(const SurfaceMesh& mesh, const tbb::blocked_range<size_t>& range, CancelPoll& poll, OutT&& out)
{
    const Polygons polygons{mesh};
    const size_t triangleCount = mesh.triangles.size();
#if defined(__SSE2__)
    const float* xyz = mesh.points.front().asPointer();
    const uint32_t lastPoint = uint32_t(mesh.points.size() - 1);
    const auto at = [&](uint32_t i) { return _mm_loadu_ps(xyz + 3 * size_t(i)); };
    const auto store = [&](size_t n, __m128 sum) {
        alignas(16) float lanes[4];
        _mm_store_ps(lanes, sum);
        out(n, Vec3s(lanes[0], lanes[1], lanes[2]));
    };
#endif
    for (size_t n = range.begin(); n < range.end(); ++n) {
        if (poll.stoppedAt(n - range.begin())) return;
#if defined(__SSE2__)
        if (n >= triangleCount) {
            const openvdb::Vec4I& q = mesh.quads[n - triangleCount];
            if (std::max(std::max(q[0], q[1]), std::max(q[2], q[3])) != lastPoint) {
                const __m128 sum = _mm_add_ps(_mm_add_ps(_mm_add_ps(at(q[0]), at(q[1])), at(q[2])), at(q[3]));
                store(n, _mm_mul_ps(sum, _mm_set1_ps(0.25f)));
                continue;
            }
        } else {
            const openvdb::Vec3I& t = mesh.triangles[n];
            if (std::max(std::max(t[0], t[1]), t[2]) != lastPoint) {
                const __m128 sum = _mm_add_ps(_mm_add_ps(at(t[0]), at(t[1])), at(t[2]));
                store(n, _mm_mul_ps(sum, _mm_set1_ps(1.0f / 3.0f)));
                continue;
            }
        }
#endif
        out(n, centroidOf(polygons[n], mesh.points));
    }
}

/// Centroid, area and unit normal of every polygon.
void measurePolygons(const Polygons& polygons, const std::vector<Vec3s>& points, UnwrittenVector<Vec3s>& centroid,
                     UnwrittenVector<float>& area, UnwrittenVector<Vec3s>& normal, CancelPoll& poll)
{
    tbb::parallel_for(tbb::blocked_range<size_t>(0, polygons.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t n = range.begin(); n < range.end(); ++n) {
                if (poll.stoppedAt(n - range.begin())) return;
                const Corners t = polygons[n];
                centroid[n] = centroidOf(t, points);
                const Vec3s a = points[t.vertex[0]], b = points[t.vertex[1]], c = points[t.vertex[2]];
                const Vec3s cross = t.count == 4 ? twiceVectorArea(a, b, c, points[t.vertex[3]]) : twiceVectorArea(a, b, c);
                const float length = cross.length();
                area[n] = 0.5f * length;
                normal[n] = length > 0.0f ? cross / length : Vec3s(0.0f);
            }
        });
    poll.throwIfStopped();
}

/// Call @a fn(n) for the items (polygons, vertices) of a range of LaneLists' groups, one at a
/// time: the plain copy of a round. Asks @a poll as often as the vector copies do.
template<typename FnT>
void forEachItemOf(const tbb::blocked_range<size_t>& groups, size_t lanes, size_t itemCount, CancelPoll& poll, FnT&& fn)
{
    for (size_t g = groups.begin(); g < groups.end(); ++g) {
        if (poll.stoppedAt((g - groups.begin()) * lanes)) return;
        for (size_t n = g * lanes; n < std::min((g + 1) * lanes, itemCount); ++n) fn(n);
    }
}

/// One normal round: every polygon's filtered normal from the previous round's normals
/// (see smoothSurface()), over ranges of the neighbour lists' groups (PolygonNeighbours).
/// The same operations in the same order for every polygon, so the bits do not depend on
/// the threads, the ranges, or which copy of the loop runs.
struct NormalRoundOp
{
    const PolygonNeighbours& neighbours;
    /// The polygons' normals, and one more (zero) at the end: the vector copies load 16
    /// bytes from a normal's x, reading the next normal's x too.
    const UnwrittenVector<Vec3s>& normal;
    UnwrittenVector<Vec3s>& filtered;  ///< as normal
    size_t polygonCount;
    float normalScale;
    CancelPoll& poll;
    bool avx512;  ///< run the AVX-512F copy of the loop (InstructionSet.h); lanes == 16
    bool avx2;    ///< else the AVX2 copy; lanes == 8

    void operator()(const tbb::blocked_range<size_t>& groups) const
    {
#if NONBLOPPY_HAS_AVX2_COPY
        if (avx512) { filterAvx512(groups); return; }
        if (avx2) { filterAvx2(groups); return; }
#endif
        forEachItemOf(groups, neighbours.lanes, polygonCount, poll, [&](size_t n) { filterOne(n); });
    }

    void filterOne(size_t n) const
    {
        const Vec3s own = normal[n];
        float x = 0.0f, y = 0.0f, z = 0.0f;
        const size_t lanes = neighbours.lanes;
        const uint64_t first = neighbours.entry(n, 0);
        for (uint32_t k = 0; k < neighbours.count[n]; ++k) {
            const uint64_t e = first + uint64_t(k) * lanes;
            const Vec3s other = normal[neighbours.polygon[e]];
            const float dx = other[0] - own[0], dy = other[1] - own[1], dz = other[2] - own[2];
            const float w = neighbours.weight[e] * exp_internal::expNonPositive(-normalScale * (dx * dx + dy * dy + dz * dz));
            x += w * other[0];
            y += w * other[1];
            z += w * other[2];
        }
        const float length = std::sqrt(x * x + y * y + z * z);
        filtered[n] = length > 0.0f ? Vec3s(x / length, y / length, z / length) : own;
    }

#if NONBLOPPY_HAS_AVX2_COPY
    /// What a vector copy loads for the @a Lanes polygons of group @a g, one per lane: their
    /// neighbour counts, the longest, and each polygon's own normal. Lanes past the last
    /// polygon have no neighbours.
    template<int Lanes>
    struct LaneGroup
    {
        alignas(64) int32_t count[Lanes];
        alignas(64) float ownX[Lanes];
        alignas(64) float ownY[Lanes];
        alignas(64) float ownZ[Lanes];
        int lanes = Lanes;  ///< polygons in the group: fewer in the last one
        int32_t most = 0;
    };

    template<int Lanes>
    __attribute__((always_inline)) inline void loadGroup(size_t g, LaneGroup<Lanes>& group) const
    {
        const size_t n = g * Lanes;
        group.lanes = int(std::min(size_t(Lanes), polygonCount - n));
        group.most = int32_t((neighbours.groupStart[g + 1] - neighbours.groupStart[g]) / Lanes);
        for (int l = 0; l < Lanes; ++l) {
            group.count[l] = int32_t(neighbours.count[n + size_t(l)]);  // zero past the last polygon
            const Vec3s own = l < group.lanes ? normal[n + size_t(l)] : Vec3s(0.0f);
            group.ownX[l] = own[0];
            group.ownY[l] = own[1];
            group.ownZ[l] = own[2];
        }
    }

    /// The filtered normals of the group's polygons from @a n, from their sums divided by
    /// their lengths (computed per lane as filterOne() does); a zero sum keeps the normal.
    void storeGroup(size_t n, int lanes, const float* unitX, const float* unitY, const float* unitZ,
                    const float* lengths) const
    {
        for (int l = 0; l < lanes; ++l) {
            filtered[n + size_t(l)] = lengths[l] > 0.0f ? Vec3s(unitX[l], unitY[l], unitZ[l]) : normal[n + size_t(l)];
        }
    }

    /// The normals (x, y, z and one float more) of the polygons @a j[0], j[4], j[8] and j[12],
    /// a quarter of the register each.
    NONBLOPPY_TARGET_AVX512 static __attribute__((always_inline)) inline __m512 fourNormals(const float* normals,
                                                                                            const uint32_t* j)
    {
        __m512 r = _mm512_castps128_ps512(_mm_loadu_ps(normals + 3 * size_t(j[0])));
        r = _mm512_insertf32x4(r, _mm_loadu_ps(normals + 3 * size_t(j[4])), 1);
        r = _mm512_insertf32x4(r, _mm_loadu_ps(normals + 3 * size_t(j[8])), 2);
        return _mm512_insertf32x4(r, _mm_loadu_ps(normals + 3 * size_t(j[12])), 3);
    }

    /// filterAvx2() with sixteen polygons at a time (AVX-512F): the same operations in each
    /// lane, so the same bits. The exponential's multiplies and adds dominate the AVX2 copy;
    /// sixteen lanes do twice as many per instruction. On the 64x benchmark input with
    /// `--spacing 0.0467157`, two threads, three alternating pairs against the AVX2 copy: the
    /// smooth stage 3.15–3.17 → 2.82–2.86 s, the run 4.93–4.97 → 4.63–4.64 s (Intel Xeon).
    /// Each step's neighbours and weights come side by side from the lists (PolygonNeighbours)
    /// where the lanes gathered them: on an AMD EPYC (Zen 4), whose gathers are slow, a normal
    /// round 55 → 33 ms, the smooth stage 3.78–4.00 → 2.99–3.07 s, the run 5.53–5.94 → 4.81–4.97 s
    /// (two alternating pairs, the same output bytes), peak RSS 569–571 → 579–582 MB. The
    /// neighbours' normals loaded and transposed instead of gathered: smooth stage 2.88–2.89 →
    /// 2.49–2.52 s, the run 4.61–4.73 → 4.27–4.36 s (three pairs); the AVX2 copy's normal
    /// rounds and setup 1.84 → 1.47–1.52 s on the same machine.
    NONBLOPPY_TARGET_AVX512 void filterAvx512(const tbb::blocked_range<size_t>& groups) const
    {
        const uint32_t* polygonOf = neighbours.polygon.data();
        const float* weightOf = neighbours.weight.data();
        const float* normals = normal[0].asPointer();
        const __m512 negativeScale = _mm512_set1_ps(-normalScale);
        for (size_t g = groups.begin(); g < groups.end(); ++g) {
            if (poll.stoppedAt((g - groups.begin()) * 16)) return;
            const size_t n = g * 16;
            LaneGroup<16> group;
            loadGroup(g, group);
            const __m512 ox = _mm512_load_ps(group.ownX), oy = _mm512_load_ps(group.ownY);
            const __m512 oz = _mm512_load_ps(group.ownZ);
            const __m512i counts = _mm512_load_si512(group.count);
            const uint32_t* polygonStep = polygonOf + neighbours.groupStart[g];
            const float* weightStep = weightOf + neighbours.groupStart[g];
            __m512 x = _mm512_setzero_ps(), y = _mm512_setzero_ps(), z = _mm512_setzero_ps();
            for (int32_t k = 0; k < group.most; ++k, polygonStep += 16, weightStep += 16) {
                const __mmask16 active = _mm512_cmpgt_epi32_mask(counts, _mm512_set1_epi32(k));  // k < count
                const __m512 base = _mm512_maskz_loadu_ps(active, weightStep);
                // The neighbours' normals: one 16-byte load each (padding entries name real
                // polygons), four to a register, transposed into x, y and z lanes. Gathers,
                // slow on AMD's Zen 4, took 40% longer. (maskz forms: see expNonPositiveAvx512().)
                const __m512 r0 = fourNormals(normals, polygonStep), r1 = fourNormals(normals, polygonStep + 1);
                const __m512 r2 = fourNormals(normals, polygonStep + 2), r3 = fourNormals(normals, polygonStep + 3);
                const __m512d xy01 = _mm512_castps_pd(_mm512_maskz_unpacklo_ps(0xFFFF, r0, r1));  // x0 x1 y0 y1 a quarter
                const __m512d xy23 = _mm512_castps_pd(_mm512_maskz_unpacklo_ps(0xFFFF, r2, r3));
                const __m512d zw01 = _mm512_castps_pd(_mm512_maskz_unpackhi_ps(0xFFFF, r0, r1));  // z0 z1 . . a quarter
                const __m512d zw23 = _mm512_castps_pd(_mm512_maskz_unpackhi_ps(0xFFFF, r2, r3));
                const __m512 nx = _mm512_castpd_ps(_mm512_maskz_unpacklo_pd(0xFF, xy01, xy23));
                const __m512 ny = _mm512_castpd_ps(_mm512_maskz_unpackhi_pd(0xFF, xy01, xy23));
                const __m512 nz = _mm512_castpd_ps(_mm512_maskz_unpacklo_pd(0xFF, zw01, zw23));
                const __m512 dx = _mm512_sub_ps(nx, ox), dy = _mm512_sub_ps(ny, oy), dz = _mm512_sub_ps(nz, oz);
                const __m512 d2 = _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(dx, dx), _mm512_mul_ps(dy, dy)),
                                                _mm512_mul_ps(dz, dz));
                const __m512 w =
                    _mm512_mul_ps(base, exp_internal::expNonPositiveAvx512(_mm512_mul_ps(negativeScale, d2)));
                // Lanes past their polygon's last neighbour keep their sums as they are.
                x = _mm512_mask_add_ps(x, active, x, _mm512_mul_ps(w, nx));
                y = _mm512_mask_add_ps(y, active, y, _mm512_mul_ps(w, ny));
                z = _mm512_mask_add_ps(z, active, z, _mm512_mul_ps(w, nz));
            }
            const __m512 length = _mm512_maskz_sqrt_ps(  // maskz: see expNonPositiveAvx512()
                0xFFFF, _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(x, x), _mm512_mul_ps(y, y)), _mm512_mul_ps(z, z)));
            alignas(64) float unitX[16], unitY[16], unitZ[16], lengths[16];
            _mm512_store_ps(unitX, _mm512_div_ps(x, length));
            _mm512_store_ps(unitY, _mm512_div_ps(y, length));
            _mm512_store_ps(unitZ, _mm512_div_ps(z, length));
            _mm512_store_ps(lengths, length);
            storeGroup(n, group.lanes, unitX, unitY, unitZ, lengths);
        }
    }

    /// The normals (x, y, z and one float more) of the polygons @a j[0] and j[4], a half of
    /// the register each.
    NONBLOPPY_TARGET_AVX2 static __attribute__((always_inline)) inline __m256 twoNormals(const float* normals,
                                                                                         const uint32_t* j)
    {
        return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(normals + 3 * size_t(j[0]))),
                                    _mm_loadu_ps(normals + 3 * size_t(j[4])), 1);
    }

    /// Eight polygons at a time, a lane each: each step's neighbours and weights loaded side
    /// by side, and the neighbours' normals.
    NONBLOPPY_TARGET_AVX2 void filterAvx2(const tbb::blocked_range<size_t>& groups) const
    {
        const uint32_t* polygonOf = neighbours.polygon.data();
        const float* weightOf = neighbours.weight.data();
        const float* normals = normal[0].asPointer();
        const __m256 negativeScale = _mm256_set1_ps(-normalScale);
        for (size_t g = groups.begin(); g < groups.end(); ++g) {
            if (poll.stoppedAt((g - groups.begin()) * 8)) return;
            const size_t n = g * 8;
            LaneGroup<8> group;
            loadGroup(g, group);
            const __m256 ox = _mm256_load_ps(group.ownX), oy = _mm256_load_ps(group.ownY);
            const __m256 oz = _mm256_load_ps(group.ownZ);
            const __m256i counts = _mm256_load_si256(reinterpret_cast<const __m256i*>(group.count));
            const uint32_t* polygonStep = polygonOf + neighbours.groupStart[g];
            const float* weightStep = weightOf + neighbours.groupStart[g];
            __m256 x = _mm256_setzero_ps(), y = _mm256_setzero_ps(), z = _mm256_setzero_ps();
            for (int32_t k = 0; k < group.most; ++k, polygonStep += 8, weightStep += 8) {
                const __m256i activeBits = _mm256_cmpgt_epi32(counts, _mm256_set1_epi32(k));  // k < count
                const __m256 active = _mm256_castsi256_ps(activeBits);
                const __m256 base = _mm256_and_ps(_mm256_loadu_ps(weightStep), active);
                // The neighbours' normals as in filterAvx512(), two to a register.
                const __m256 r0 = twoNormals(normals, polygonStep), r1 = twoNormals(normals, polygonStep + 1);
                const __m256 r2 = twoNormals(normals, polygonStep + 2), r3 = twoNormals(normals, polygonStep + 3);
                const __m256d xy01 = _mm256_castps_pd(_mm256_unpacklo_ps(r0, r1));  // x0 x1 y0 y1 a half
                const __m256d xy23 = _mm256_castps_pd(_mm256_unpacklo_ps(r2, r3));
                const __m256d zw01 = _mm256_castps_pd(_mm256_unpackhi_ps(r0, r1));  // z0 z1 . . a half
                const __m256d zw23 = _mm256_castps_pd(_mm256_unpackhi_ps(r2, r3));
                const __m256 nx = _mm256_castpd_ps(_mm256_unpacklo_pd(xy01, xy23));
                const __m256 ny = _mm256_castpd_ps(_mm256_unpackhi_pd(xy01, xy23));
                const __m256 nz = _mm256_castpd_ps(_mm256_unpacklo_pd(zw01, zw23));
                const __m256 dx = _mm256_sub_ps(nx, ox), dy = _mm256_sub_ps(ny, oy), dz = _mm256_sub_ps(nz, oz);
                const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                                                _mm256_mul_ps(dz, dz));
                const __m256 w = _mm256_mul_ps(base, exp_internal::expNonPositiveAvx2(_mm256_mul_ps(negativeScale, d2)));
                // Lanes past their polygon's last neighbour keep their sums as they are.
                x = _mm256_blendv_ps(x, _mm256_add_ps(x, _mm256_mul_ps(w, nx)), active);
                y = _mm256_blendv_ps(y, _mm256_add_ps(y, _mm256_mul_ps(w, ny)), active);
                z = _mm256_blendv_ps(z, _mm256_add_ps(z, _mm256_mul_ps(w, nz)), active);
            }
            const __m256 length = _mm256_sqrt_ps(
                _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(x, x), _mm256_mul_ps(y, y)), _mm256_mul_ps(z, z)));
            alignas(32) float unitX[8], unitY[8], unitZ[8], lengths[8];
            _mm256_store_ps(unitX, _mm256_div_ps(x, length));
            _mm256_store_ps(unitY, _mm256_div_ps(y, length));
            _mm256_store_ps(unitZ, _mm256_div_ps(z, length));
            _mm256_store_ps(lengths, length);
            storeGroup(n, group.lanes, unitX, unitY, unitZ, lengths);
        }
    }
#endif
};

/// A polygon's filtered normal and its centroid, side by side: a vertex round reads both
/// for each polygon around a vertex, from one cache line instead of two.
struct Plane
{
    Vec3s normal, centroid;
};

/// One vertex round: every vertex moved by the mean over its polygons of n (n · (c − v)),
/// over ranges of vertexLanes()' groups. Each lane does moveOne()'s operations in its order,
/// so the bits do not depend on the threads or on the copy that runs.
struct VertexRoundOp
{
    const LaneLists& around;
    /// The polygons' planes, and one more at the end: the vector copies load 32 bytes from
    /// a plane's start, reading 8 bytes of the next one.
    const UnwrittenVector<Plane>& planes;
    const std::vector<Vec3s>& points;
    std::vector<Vec3s>& next;
    CancelPoll& poll;
    bool avx512;  ///< run the AVX-512F copy (InstructionSet.h); lanes == 8
    bool avx2;    ///< else the AVX2 copy; lanes == 8

    void operator()(const tbb::blocked_range<size_t>& groups) const
    {
#if NONBLOPPY_HAS_AVX2_COPY
        if (avx512) { moveAvx512(groups); return; }
        if (avx2) { moveAvx2(groups); return; }
#endif
        forEachItemOf(groups, around.lanes, points.size(), poll, [&](size_t v) { moveOne(v); });
    }

    void moveOne(size_t v) const
    {
        const Vec3s p = points[v];
        const uint32_t count = around.count[v];
        if (count == 0) {
            next[v] = p;
            return;
        }
        const uint64_t first = around.entry(v, 0);
        Vec3d move(0.0);
        for (uint32_t k = 0; k < count; ++k) {
            const Plane& plane = planes[around.polygon[first + uint64_t(k) * around.lanes]];
            move += Vec3d(plane.normal) * double(plane.normal.dot(plane.centroid - p));
        }
        next[v] = p + Vec3s(move / double(count));
    }

#if NONBLOPPY_HAS_AVX2_COPY
    /// For the eight polygons @a step[0..8) and the points (px, py, pz), a lane each: the
    /// polygons' normals n and n · (c − p) in floats, as moveOne() computes them. Each plane
    /// is loaded whole (32 bytes from its start: its six floats and two more) and the eight
    /// are transposed.
    NONBLOPPY_TARGET_AVX2 static __attribute__((always_inline)) inline void normalsAndDots(
        const float* planeFloats, const uint32_t* step, __m256 px, __m256 py, __m256 pz, __m256& nx, __m256& ny,
        __m256& nz, __m256& dot)
    {
        __m256 r[8];
        for (int l = 0; l < 8; ++l) r[l] = _mm256_loadu_ps(planeFloats + 6 * size_t(step[l]));
        const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
        const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
        const __m256 t4 = _mm256_unpacklo_ps(r[4], r[5]), t5 = _mm256_unpackhi_ps(r[4], r[5]);
        const __m256 t6 = _mm256_unpacklo_ps(r[6], r[7]), t7 = _mm256_unpackhi_ps(r[6], r[7]);
        // Lanes 0-3 | 4-7 of: nx | cy, ny | cz, nz | -, cx | -
        const __m256 u0 = _mm256_shuffle_ps(t0, t2, 0x44), u1 = _mm256_shuffle_ps(t0, t2, 0xEE);
        const __m256 u2 = _mm256_shuffle_ps(t1, t3, 0x44), u3 = _mm256_shuffle_ps(t1, t3, 0xEE);
        const __m256 u4 = _mm256_shuffle_ps(t4, t6, 0x44), u5 = _mm256_shuffle_ps(t4, t6, 0xEE);
        const __m256 u6 = _mm256_shuffle_ps(t5, t7, 0x44), u7 = _mm256_shuffle_ps(t5, t7, 0xEE);
        nx = _mm256_permute2f128_ps(u0, u4, 0x20);
        ny = _mm256_permute2f128_ps(u1, u5, 0x20);
        nz = _mm256_permute2f128_ps(u2, u6, 0x20);
        const __m256 cx = _mm256_permute2f128_ps(u3, u7, 0x20);
        const __m256 cy = _mm256_permute2f128_ps(u0, u4, 0x31), cz = _mm256_permute2f128_ps(u1, u5, 0x31);
        const __m256 dx = _mm256_sub_ps(cx, px), dy = _mm256_sub_ps(cy, py), dz = _mm256_sub_ps(cz, pz);
        dot = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nx, dx), _mm256_mul_ps(ny, dy)), _mm256_mul_ps(nz, dz));
    }

    /// Load the points of the group from @a n into lanes (zero past the last point).
    void loadPoints(size_t n, int lanes, float* ownX, float* ownY, float* ownZ) const
    {
        for (int l = 0; l < 8; ++l) {
            const Vec3s p = l < lanes ? points[n + size_t(l)] : Vec3s(0.0f);
            ownX[l] = p[0];
            ownY[l] = p[1];
            ownZ[l] = p[2];
        }
    }

    /// Store p + move for the group's vertices from @a n; a vertex without polygons keeps p.
    void storePoints(size_t n, int lanes, const float* moveX, const float* moveY, const float* moveZ) const
    {
        for (int l = 0; l < lanes; ++l) {
            const Vec3s p = points[n + size_t(l)];
            next[n + size_t(l)] = around.count[n + size_t(l)] == 0 ? p : p + Vec3s(moveX[l], moveY[l], moveZ[l]);
        }
    }

    /// @a sum + @a term in the lanes @a mask (all bits set) selects; @a sum elsewhere.
    NONBLOPPY_TARGET_AVX2 static __attribute__((always_inline)) inline void accumulate(__m256d& sum, __m256d mask,
                                                                                       __m256d term)
    {
        sum = _mm256_blendv_pd(sum, _mm256_add_pd(sum, term), mask);
    }

    /// @a out[0..8): the two halves' sums divided by their counts, as floats.
    NONBLOPPY_TARGET_AVX2 static __attribute__((always_inline)) inline void divided(float* out, __m256d low,
                                                                                    __m256d high, __m256d countLow,
                                                                                    __m256d countHigh)
    {
        _mm_store_ps(out, _mm256_cvtpd_ps(_mm256_div_pd(low, countLow)));
        _mm_store_ps(out + 4, _mm256_cvtpd_ps(_mm256_div_pd(high, countHigh)));
    }

    /// moveAvx512() with the sums in two halves of four doubles (AVX2): the smoothing on the
    /// 64x benchmark input's surface (`--spacing 0.0467157`, two threads, AMD Zen 4 running
    /// the AVX2 copies) 2.81–2.86 → 2.55–2.56 s against moveOne() alone, two alternating
    /// pairs, the same bits.
    NONBLOPPY_TARGET_AVX2 void moveAvx2(const tbb::blocked_range<size_t>& groups) const
    {
        const float* planeFloats = planes[0].normal.asPointer();
        const __m256i signBit = _mm256_set1_epi32(INT32_MIN);  // unsigned compares as signed ones
        for (size_t g = groups.begin(); g < groups.end(); ++g) {
            if (poll.stoppedAt((g - groups.begin()) * 8)) return;
            const size_t n = g * 8;
            const int lanes = int(std::min(size_t(8), points.size() - n));
            alignas(32) float ownX[8], ownY[8], ownZ[8];
            loadPoints(n, lanes, ownX, ownY, ownZ);
            const __m256 px = _mm256_load_ps(ownX), py = _mm256_load_ps(ownY), pz = _mm256_load_ps(ownZ);
            const __m256i counts = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(around.count.data() + n));
            const __m256i biasedCounts = _mm256_xor_si256(counts, signBit);
            const uint64_t longest = (around.groupStart[g + 1] - around.groupStart[g]) / 8;
            const uint32_t* step = around.polygon.data() + around.groupStart[g];
            __m256d xLow = _mm256_setzero_pd(), yLow = _mm256_setzero_pd(), zLow = _mm256_setzero_pd();
            __m256d xHigh = _mm256_setzero_pd(), yHigh = _mm256_setzero_pd(), zHigh = _mm256_setzero_pd();
            for (uint64_t k = 0; k < longest; ++k, step += 8) {
                const __m256i active = _mm256_cmpgt_epi32(biasedCounts, _mm256_xor_si256(_mm256_set1_epi32(int(k)), signBit));
                // Each lane's 32-bit mask widened to the 64 bits of its double.
                const __m256d activeLow = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(_mm256_castsi256_si128(active)));
                const __m256d activeHigh = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(_mm256_extracti128_si256(active, 1)));
                __m256 nx, ny, nz, dot;
                normalsAndDots(planeFloats, step, px, py, pz, nx, ny, nz, dot);
                const __m256d dotLow = _mm256_cvtps_pd(_mm256_castps256_ps128(dot));
                const __m256d dotHigh = _mm256_cvtps_pd(_mm256_extractf128_ps(dot, 1));
                accumulate(xLow, activeLow, _mm256_mul_pd(_mm256_cvtps_pd(_mm256_castps256_ps128(nx)), dotLow));
                accumulate(yLow, activeLow, _mm256_mul_pd(_mm256_cvtps_pd(_mm256_castps256_ps128(ny)), dotLow));
                accumulate(zLow, activeLow, _mm256_mul_pd(_mm256_cvtps_pd(_mm256_castps256_ps128(nz)), dotLow));
                accumulate(xHigh, activeHigh, _mm256_mul_pd(_mm256_cvtps_pd(_mm256_extractf128_ps(nx, 1)), dotHigh));
                accumulate(yHigh, activeHigh, _mm256_mul_pd(_mm256_cvtps_pd(_mm256_extractf128_ps(ny, 1)), dotHigh));
                accumulate(zHigh, activeHigh, _mm256_mul_pd(_mm256_cvtps_pd(_mm256_extractf128_ps(nz, 1)), dotHigh));
            }
            // Lanes without polygons divide 0 by 0 here; they keep their point (storePoints()).
            alignas(32) uint32_t countOf[8];
            _mm256_store_si256(reinterpret_cast<__m256i*>(countOf), counts);
            const __m256d countLow = _mm256_setr_pd(countOf[0], countOf[1], countOf[2], countOf[3]);
            const __m256d countHigh = _mm256_setr_pd(countOf[4], countOf[5], countOf[6], countOf[7]);
            alignas(32) float moveX[8], moveY[8], moveZ[8];
            divided(moveX, xLow, xHigh, countLow, countHigh);
            divided(moveY, yLow, yHigh, countLow, countHigh);
            divided(moveZ, zLow, zHigh, countLow, countHigh);
            storePoints(n, lanes, moveX, moveY, moveZ);
        }
    }

    /// Eight vertices at a time, a lane each: each step's polygons' planes loaded (32 bytes
    /// each) and transposed, the dot products in floats and the sums in doubles, as
    /// moveOne() does them. On the 64x benchmark input with `--spacing 0.0467157`, two
    /// threads, an AMD EPYC (Zen 4), three alternating pairs against moveOne() alone: smooth
    /// stage 2.49–2.58 → 2.22–2.32 s, the run 4.25–4.43 → 4.06–4.18 s, the same output bytes.
    /// (Gathering the planes' six floats instead was slower than moveOne().)
    NONBLOPPY_TARGET_AVX512 void moveAvx512(const tbb::blocked_range<size_t>& groups) const
    {
        const float* planeFloats = planes[0].normal.asPointer();
        for (size_t g = groups.begin(); g < groups.end(); ++g) {
            if (poll.stoppedAt((g - groups.begin()) * 8)) return;
            const size_t n = g * 8;
            const int lanes = int(std::min(size_t(8), points.size() - n));
            alignas(32) float ownX[8], ownY[8], ownZ[8];
            loadPoints(n, lanes, ownX, ownY, ownZ);
            const __m256 px = _mm256_load_ps(ownX), py = _mm256_load_ps(ownY), pz = _mm256_load_ps(ownZ);
            const __m256i counts = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(around.count.data() + n));
            const __m512i wideCounts = _mm512_maskz_mov_epi32(0x00FF, _mm512_castsi256_si512(counts));
            const uint64_t longest = (around.groupStart[g + 1] - around.groupStart[g]) / 8;
            const uint32_t* step = around.polygon.data() + around.groupStart[g];
            __m512d x = _mm512_setzero_pd(), y = _mm512_setzero_pd(), z = _mm512_setzero_pd();
            for (uint64_t k = 0; k < longest; ++k, step += 8) {
                const __mmask8 active = __mmask8(_mm512_cmpgt_epu32_mask(wideCounts, _mm512_set1_epi32(int(k))));
                __m256 nx, ny, nz, dot;
                normalsAndDots(planeFloats, step, px, py, pz, nx, ny, nz, dot);
                const __m512d dotWide = _mm512_maskz_cvtps_pd(0xFF, dot);  // maskz: see expNonPositiveAvx512()
                x = _mm512_mask_add_pd(x, active, x, _mm512_mul_pd(_mm512_maskz_cvtps_pd(0xFF, nx), dotWide));
                y = _mm512_mask_add_pd(y, active, y, _mm512_mul_pd(_mm512_maskz_cvtps_pd(0xFF, ny), dotWide));
                z = _mm512_mask_add_pd(z, active, z, _mm512_mul_pd(_mm512_maskz_cvtps_pd(0xFF, nz), dotWide));
            }
            // Lanes without polygons divide 0 by 0 here; they keep their point below.
            const __m512d count = _mm512_maskz_cvtepu32_pd(0xFF, counts);
            alignas(32) float moveX[8], moveY[8], moveZ[8];
            _mm256_store_ps(moveX, _mm512_maskz_cvtpd_ps(0xFF, _mm512_div_pd(x, count)));
            _mm256_store_ps(moveY, _mm512_maskz_cvtpd_ps(0xFF, _mm512_div_pd(y, count)));
            _mm256_store_ps(moveZ, _mm512_maskz_cvtpd_ps(0xFF, _mm512_div_pd(z, count)));
            storePoints(n, lanes, moveX, moveY, moveZ);
        }
    }
#endif
};

} // namespace

void smoothSurface(SurfaceMesh& mesh, const SmoothSettings& settings, openvdb::util::NullInterrupter* interrupter)
{
    instruction_set_internal::smoothSurface(mesh, settings, interrupter, instruction_set_internal::InstructionSet::Auto);
}

void instruction_set_internal::smoothSurface(SurfaceMesh& mesh, const SmoothSettings& settings,
                                             openvdb::util::NullInterrupter* interrupter, InstructionSet set)
{
    polygon_indices_internal::requireValidIndices(mesh);
    surface_stages_internal::smoothSurfaceUnchecked(mesh, settings, interrupter, set);
}

void surface_stages_internal::smoothSurfaceUnchecked(SurfaceMesh& mesh, const SmoothSettings& settings,
                                                     openvdb::util::NullInterrupter* interrupter,
                                                     instruction_set_internal::InstructionSet set)
{
    std::ostringstream msg;
    if (!(settings.spatialWidth > 0.0) || !std::isfinite(settings.spatialWidth)) {
        msg << "smoothing width must be > 0, got " << settings.spatialWidth;
        throw ParameterError(msg.str());
    }
    if (!(settings.normalWidth > 0.0) || !std::isfinite(settings.normalWidth)) {
        msg << "smoothing normal width must be > 0, got " << settings.normalWidth;
        throw ParameterError(msg.str());
    }
    if (settings.normalRounds < 0 || settings.vertexRounds < 0) {
        msg << "smoothing rounds must be >= 0, got " << settings.normalRounds << " normal and "
            << settings.vertexRounds << " vertex rounds";
        throw ParameterError(msg.str());
    }
    const Polygons polygons{mesh};
    if (settings.normalRounds == 0 || settings.vertexRounds == 0 || polygons.size() == 0) return;
    if (polygons.size() > UINT32_MAX) throw ParameterError("cannot smooth more than 2^32 polygons");

    const size_t polygonCount = polygons.size();
    // What the neighbour lists' counts and the per-polygon arrays take; the lists' entries
    // are checked once counted (polygonNeighbours()).
    const double corners = 3.0 * double(mesh.triangles.size()) + 4.0 * double(mesh.quads.size());
    requireMemoryForSmoothing(double(sizeof(uint64_t)) * double(mesh.points.size() + 1) + double(sizeof(uint32_t)) * corners
                                  + double(3 * sizeof(Vec3s) + sizeof(float)) * double(polygonCount)
                                  + double(sizeof(uint64_t)) * double(polygonCount + 1),
                              polygonCount);
    CancelPoll poll(interrupter, "smooth surface");
    const bool avx512 = instruction_set_internal::useAvx512(set);
    const bool avx2 = instruction_set_internal::useAvx2(set);
    const size_t lanes = avx512 ? 16 : avx2 ? 8 : 1;  // NormalRoundOp's copies
    VertexPolygons around = vertexPolygons(polygons, mesh.points.size(), poll);

    UnwrittenVector<Vec3s> centroid(polygonCount), normal(polygonCount + 1), filtered(polygonCount + 1);
    normal[polygonCount] = filtered[polygonCount] = Vec3s(0.0f);  // read, never used (NormalRoundOp)
    UnwrittenVector<float> area(polygonCount);
    measurePolygons(polygons, mesh.points, centroid, area, normal, poll);

    // Normal rounds: every polygon reads the previous round's normals only (double
    // buffered), in a fixed neighbour order, so the result does not depend on the threads.
    // The centroids do not move during these rounds: their part of the weight is computed once.
    const float spatialScale = float(0.5 / (settings.spatialWidth * settings.spatialWidth));
    const float normalScale = float(0.5 / (settings.normalWidth * settings.normalWidth));
    {
        const PolygonNeighbours neighbours =
            polygonNeighbours(polygons, around, centroid, area, spatialScale, lanes, poll);
        UnwrittenVector<float>().swap(area);
        for (int round = 0; round < settings.normalRounds; ++round) {
            tbb::parallel_for(tbb::blocked_range<size_t>(0, neighbours.groupStart.size() - 1),
                              NormalRoundOp{neighbours, normal, filtered, polygonCount, normalScale, poll, avx512, avx2});
            poll.throwIfStopped();
            normal.swap(filtered);
        }
    }

    // Vertex rounds: move each vertex along its polygons' filtered normals onto their planes.
    UnwrittenVector<Plane> planes(polygonCount + 1);
    planes[polygonCount] = Plane{Vec3s(0.0f), Vec3s(0.0f)};  // read, never used (VertexRoundOp)
    tbb::parallel_for(tbb::blocked_range<size_t>(0, polygonCount), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t n = range.begin(); n < range.end(); ++n) planes[n] = Plane{normal[n], centroid[n]};
    });
    UnwrittenVector<Vec3s>().swap(normal);
    UnwrittenVector<Vec3s>().swap(filtered);
    UnwrittenVector<Vec3s>().swap(centroid);
    const LaneLists vertexLists = vertexLanes(around, avx512 || avx2 ? 8 : 1, polygonCount, poll);
    around = VertexPolygons();  // its lists are in vertexLists now
    std::vector<Vec3s> next(mesh.points.size());
    for (int round = 0; round < settings.vertexRounds; ++round) {
        if (round > 0) {
            tbb::parallel_for(tbb::blocked_range<size_t>(0, polygonCount),
                [&](const tbb::blocked_range<size_t>& range) {
                    centroidsOf(mesh, range, poll, [&](size_t n, const Vec3s& c) { planes[n].centroid = c; });
                });
            poll.throwIfStopped();
        }
        tbb::parallel_for(tbb::blocked_range<size_t>(0, vertexLists.groupStart.size() - 1),
                          VertexRoundOp{vertexLists, planes, mesh.points, next, poll, avx512, avx2});
        poll.throwIfStopped();
        mesh.points.swap(next);
    }
}

} // namespace nonbloppy
