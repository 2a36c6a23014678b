// SPDX-License-Identifier: Apache-2.0
#include "Cancellation.h"
#include "InstructionSet.h"
#include "MachineMemory.h"
#include "OpenVdbScale.h"
#include "ParameterChecks.h"
#include "ParticleIndexImpl.h"
#include "SurfaceStages.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/Kernel.h>
#include <nonbloppy/RasterizeDensity.h>

#include <openvdb/tree/LeafManager.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <atomic>
#include <cstring>
#include <memory>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if NONBLOPPY_HAS_AVX2_COPY
#include <immintrin.h>
#endif
#include <cmath>
#include <limits>
#include <sstream>
#include <tuple>

namespace nonbloppy {

namespace {

using cancellation_internal::CancelPoll;
using FloatLeaf = openvdb::FloatTree::LeafNodeType;
using particle_index_internal::IndexLeaf;
using particle_index_internal::IndexTree;

/// Density leaves of a task between two polls: a leaf gathers every particle within r_e of
/// its 512 voxels, so a task of many leaves would otherwise run for milliseconds.
constexpr size_t kLeavesPerPoll = 8;

/// Bytes one density leaf takes on the heap: the node (masks, origin, buffer handle), its
/// separately allocated 512 values, and malloc's header for each.
constexpr double kBytesPerDensityLeaf = double(sizeof(FloatLeaf)) + double(FloatLeaf::SIZE * sizeof(float)) + 32.0;

/// @throw ParameterError("... would take 3.6 GB to 7.3 GB, more than the 2.7 GB this process
///        can still take: ...") if even @a fewestBytes of @a what ("the density grid (up
///        to N leaves of 8^3 voxels)") exceed what the process can still allocate
///        (memoryHeadroomBytes()). A voxel size far below the spacing made the process
///        allocate until it got std::bad_alloc ("out of memory") or the kernel ended it.
void requireMemoryFor(double fewestBytes, double mostBytes, const std::string& what, double voxelSize,
                      double effectiveRadius)
{
    machine_memory_internal::requireHeadroom(fewestBytes, [&] {
        using machine_memory_internal::formatBytes;
        std::ostringstream need;
        need.precision(3);
        need << what << " of these particles at --voxel-size " << voxelSize << " and --radius " << effectiveRadius
             << " would take " << formatBytes(fewestBytes);
        if (mostBytes > fewestBytes) need << " to " << formatBytes(mostBytes);
        return std::make_pair(need.str(), std::string("give a larger --voxel-size or a smaller --radius"));
    });
}

/// Bytes of the density grid whose leaves have @a origins (sorted, distinct): the leaves,
/// and the internal nodes above them, one per 128³ and per 4096³ voxels holding a leaf
/// (33 KB and 262 KB: isolated droplets each take nodes of their own). The upper nodes are
/// counted from the distinct lower ones, a list about a hundred times shorter.
double densityGridBytes(const std::vector<openvdb::Coord>& origins)
{
    using Node1 = openvdb::FloatTree::RootNodeType::ChildNodeType::ChildNodeType;
    using Node2 = openvdb::FloatTree::RootNodeType::ChildNodeType;
    // Masked origins are not in order (x, y, z order puts (0,8,200) before (0,16,0), whose
    // parents are (0,0,128) and (0,0,0)): sorted again, then made distinct.
    const auto keepDistinct = [](std::vector<openvdb::Coord>& coords) {
        tbb::parallel_sort(coords.begin(), coords.end());
        coords.erase(std::unique(coords.begin(), coords.end()), coords.end());
    };
    std::vector<openvdb::Coord> parents(origins.size());
    for (size_t n = 0; n < origins.size(); ++n) parents[n] = origins[n] & ~int(Node1::DIM - 1);
    keepDistinct(parents);
    const double lowerNodes = double(parents.size());
    for (openvdb::Coord& parent : parents) parent &= ~int(Node2::DIM - 1);
    keepDistinct(parents);
    return double(origins.size()) * kBytesPerDensityLeaf + lowerNodes * double(sizeof(Node1))
           + double(parents.size()) * double(sizeof(Node2));
}

/// Origins of the density leaves that may hold a voxel within r_e of a particle: for each
/// leaf of the particle index, the density leaves overlapping its active cells' bounding box
/// grown by r_e. Sorted, so the leaf order (and thus everything after) is deterministic.
/// On a stop (@a poll) the list is incomplete; the caller checks.
/// @throw ParameterError (requireMemoryFor()) if the list, or the leaves it names, cannot
///        fit in memory.
std::vector<openvdb::Coord> candidateLeafOrigins(const ParticleIndex& particles,
                                                 const openvdb::math::Transform& transform,
                                                 double effectiveRadius, CancelPoll& poll)
{
    const IndexTree& indexTree = particles.impl().grid->tree();
    const double cellSize = particles.cellSize();
    openvdb::tree::LeafManager<const IndexTree> leaves(indexTree);
    // Per index leaf, the box of the density leaf origins it reaches; counted before they
    // are listed, so that a list larger than memory is refused, not allocated.
    std::vector<openvdb::CoordBBox> reach(leaves.leafCount());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.leafCount()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t n = range.begin(); n < range.end(); ++n) {
                if (poll.stoppedAt(64 * (n - range.begin()))) return;  // every 64 index leaves
                openvdb::CoordBBox cells;
                leaves.leaf(n).evalActiveBoundingBox(cells, /*visitVoxels=*/true);
                const openvdb::Vec3d worldMin = (cells.min().asVec3d() - 0.5) * cellSize - effectiveRadius;
                const openvdb::Vec3d worldMax = (cells.max().asVec3d() + 0.5) * cellSize + effectiveRadius;
                const openvdb::Vec3d indexMin = transform.worldToIndex(worldMin);
                const openvdb::Vec3d indexMax = transform.worldToIndex(worldMax);
                reach[n] = openvdb::CoordBBox(openvdb::Coord::ceil(indexMin) & ~int(FloatLeaf::DIM - 1),
                                              openvdb::Coord::floor(indexMax) & ~int(FloatLeaf::DIM - 1));
            }
        });
    std::vector<openvdb::Coord> all;
    if (poll.stopped()) return all;
    double listed = 0.0;
    for (const openvdb::CoordBBox& box : reach) {
        double origins = 1.0;
        for (int k = 0; k < 3; ++k) origins *= std::max(0.0, double(box.max()[k] - box.min()[k]) / FloatLeaf::DIM + 1.0);
        listed += origins;
    }
    const double voxelSize = transform.voxelSize()[0];
    // Listed per thread, then gathered: twice the list at the peak.
    const double listBytes = 2.0 * listed * double(sizeof(openvdb::Coord));
    requireMemoryFor(listBytes, listBytes, "listing the density leaves", voxelSize, effectiveRadius);

    tbb::enumerable_thread_specific<std::vector<openvdb::Coord>> perThread;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, reach.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            std::vector<openvdb::Coord>& origins = perThread.local();
            for (size_t n = range.begin(); n < range.end(); ++n) {
                if (poll.stoppedAt(64 * (n - range.begin()))) return;
                const openvdb::Coord lo = reach[n].min(), hi = reach[n].max();
                openvdb::Coord origin;
                for (origin[0] = lo[0]; origin[0] <= hi[0]; origin[0] += FloatLeaf::DIM)
                    for (origin[1] = lo[1]; origin[1] <= hi[1]; origin[1] += FloatLeaf::DIM)
                        for (origin[2] = lo[2]; origin[2] <= hi[2]; origin[2] += FloatLeaf::DIM)
                            origins.push_back(origin);
            }
        });
    if (poll.stopped()) return all;
    all.reserve(size_t(listed));
    for (auto& origins : perThread) {
        all.insert(all.end(), origins.begin(), origins.end());
        std::vector<openvdb::Coord>().swap(origins);
    }
    // Coord's < is a total order, so the parallel sort gives std::sort's result; it can be
    // stopped (hundreds of thousands of origins, tens of ms).
    cancellation_internal::runStoppable(poll, [&] { tbb::parallel_sort(all.begin(), all.end()); });
    if (poll.stopped()) return all;
    all.erase(std::unique(all.begin(), all.end()), all.end());
    std::ostringstream what;
    what << "the density grid (up to " << all.size() << " leaves of 8^3 voxels)";
    // The candidates are boxes around the particles; the leaves a kernel reaches are fewer,
    // half as many around isolated droplets (the 29,791 of a 31³ lattice 500 spacings
    // apart: 6.7 GB counted, a 4.3 GB peak). Refused only when half would not fit.
    const double mostBytes = densityGridBytes(all);
    requireMemoryFor(0.5 * mostBytes, mostBytes, what.str(), voxelSize, effectiveRadius);
    return all;
}

/// floor and ceil to int without a libm call (x86-64's baseline SSE2 has no roundss).
inline int floorToInt(float x)
{
    const int truncated = int(x);
    return truncated - (x < float(truncated) ? 1 : 0);
}
inline int ceilToInt(float x)
{
    const int truncated = int(x);
    return truncated + (x > float(truncated) ? 1 : 0);
}

/// A column: the leaves that one task fills together, up to kColumnLeaves stacked along z
/// in each of kColumnStacks × kColumnStacks (x, y) positions. With the default r_e = 2 s and
/// h = s/2, a particle's support is 8 voxels tall (9 when it sits exactly on a voxel centre),
/// so it straddles almost every leaf boundary it meets: filled a leaf at a time, each of its
/// rows cost two 8-lane evaluations, one per leaf. In a column it costs one, unless it
/// straddles the column's ends (7 in 64 positions). Measured on the 64x dam-break input:
/// rasterization 0.92 → 0.65 s; 8 leaves were 7% faster than 4.
/// The width: each particle costs a fixed amount per column its query box meets (the index
/// lookup, its voxel range, its z-vectors), and that box, r_e wider than the column on each
/// side and rounded out to index cells, meets about 5 columns one leaf wide and 1.7 four
/// leaves wide. Same input, medians of 5 alternating runs: one thread 0.66 s one stack wide,
/// 0.55 s 4 × 4 (a 295 KB scratch block per thread, in L2); two threads (7 runs) 0.35 s and
/// 0.30 s. 2 × 2 and 8 × 8, and 16 or 32 leaves tall, were no faster than 4 × 4 by 8.
constexpr int kColumnLeaves = 8;
constexpr int kColumnVoxels = kColumnLeaves * int(FloatLeaf::DIM);
/// Leaf stacks per column along x and along y (a power of two, at most 5 bits of a mask).
constexpr int kColumnStacks = 4;
static_assert(kColumnStacks * kColumnStacks <= 32, "a column's stacks are a 32-bit mask");
/// Voxels of a column along x and along y.
constexpr int kColumnWidth = kColumnStacks * int(FloatLeaf::DIM);
/// Row length of a column's scratch block: a vector may start at the column's last voxel.
constexpr int kColumnRowStride = kColumnVoxels + 8;

/// A particle's z-span inside a column, as 8-voxel vectors, each starting at column voxel
/// @c start, with per-lane squared z-distances that every row of the particle reuses. Lanes
/// outside the support's z-range hold an infinite distance instead, as rows outside its disc
/// do, so their weight r_e/∞ − 1 < 0 is clamped to +0: the z-range needs no mask of its own.
/// The z-distance of a voxel is measured from its own leaf's origin, exactly as a
/// leaf-at-a-time evaluation would, so the values do not depend on how leaves are grouped
/// into columns.
struct ZSpan
{
    static constexpr int kMaxVectors = kColumnVoxels / 8;
    int count = 0;                                ///< vectors used: 1 for a span of 8 voxels or fewer
    int start[kMaxVectors] = {};                  ///< first column voxel of each vector
    alignas(32) float dz2[kMaxVectors][8];        ///< (z_voxel − p_z)² per lane, or +∞ outside the support
};

/// The weights w = max(r_e / √max(d², d_min²) − 1, 0) of one 8-lane vector of a row, added to
/// @a row (lanes beyond r_e add +0, which leaves any sum ≥ +0 as it is). Baseline copy: two SSE
/// halves, or scalar; IEEE sqrt and division give the AVX2 copy's bits.
inline void addRowVector(float* row, const float* dz2, float dxy2, float radius,
                         float minDistance2)
{
#if defined(__SSE2__)
    const __m128 vdxy2 = _mm_set1_ps(dxy2), vradius = _mm_set1_ps(radius), vmin = _mm_set1_ps(minDistance2);
    const __m128 one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps();
    for (int half = 0; half < 2; ++half) {
        const __m128 d2 = _mm_add_ps(vdxy2, _mm_load_ps(dz2 + 4 * half));
        __m128 w = _mm_sub_ps(_mm_div_ps(vradius, _mm_sqrt_ps(_mm_max_ps(d2, vmin))), one);
        w = _mm_max_ps(w, zero);
        _mm_storeu_ps(row + 4 * half, _mm_add_ps(_mm_loadu_ps(row + 4 * half), w));
    }
#else
    for (int l = 0; l < 8; ++l) {
        const float w = radius / std::sqrt(std::max(dxy2 + dz2[l], minDistance2)) - 1.0f;
        if (w > 0.0f) row[l] += w;
    }
#endif
}

#if NONBLOPPY_HAS_AVX2_COPY
/// addRowVector() for the AVX2 copy of the loop (InstructionSet.h): one register per vector.
NONBLOPPY_TARGET_AVX2 inline void addRowVectorAvx2(float* row, const float* dz2,
                                                   float dxy2, float radius, float minDistance2)
{
    const __m256 d2 = _mm256_add_ps(_mm256_set1_ps(dxy2), _mm256_load_ps(dz2));
    const __m256 distance = _mm256_sqrt_ps(_mm256_max_ps(d2, _mm256_set1_ps(minDistance2)));
    __m256 w = _mm256_sub_ps(_mm256_div_ps(_mm256_set1_ps(radius), distance), _mm256_set1_ps(1.0f));
    w = _mm256_max_ps(w, _mm256_setzero_ps());
    _mm256_storeu_ps(row, _mm256_add_ps(_mm256_loadu_ps(row), w));
}
#endif

/// A run [first, end) of the column order (groupColumns()) that forms one column.
struct Column
{
    size_t first;
    size_t end;
};

/// The x and y of the column holding the leaf at @a origin (its first voxel).
inline std::pair<int, int> columnOf(const openvdb::Coord& origin)
{
    return {origin[0] & ~(kColumnWidth - 1), origin[1] & ~(kColumnWidth - 1)};
}

/// Groups the sorted leaf origins into columns: origins in the same kColumnWidth² cell of
/// x and y, at most kColumnVoxels apart in z from the column's first. @a order lists the
/// origins' indices column by column, each column's in z order.
std::vector<Column> groupColumns(const std::vector<openvdb::Coord>& origins, std::vector<size_t>& order)
{
    order.resize(origins.size());
    for (size_t n = 0; n < order.size(); ++n) order[n] = n;
    const auto key = [&](size_t n) {
        const auto [x, y] = columnOf(origins[n]);
        return std::make_tuple(x, y, origins[n][2], n);
    };
    tbb::parallel_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return key(a) < key(b); });
    std::vector<Column> columns;
    for (size_t n = 0; n < order.size();) {
        const openvdb::Coord& first = origins[order[n]];
        size_t end = n + 1;
        while (end < order.size() && columnOf(origins[order[end]]) == columnOf(first) &&
               origins[order[end]][2] - first[2] < kColumnVoxels) {
            ++end;
        }
        columns.push_back({n, end});
        n = end;
    }
    return columns;
}

/// The leaf at @a origin from a column's scratch block (@a rows: its first voxel, in rows of
/// kColumnRowStride floats, kColumnWidth rows per x): values copied as they are, voxels with a positive sum active
/// (the others hold +0, the background). Null if no voxel is active.
FloatLeaf* makeLeaf(const openvdb::Coord& origin, const float* rows)
{
    constexpr int kDim = int(FloatLeaf::DIM);
    std::unique_ptr<FloatLeaf> leaf(new FloatLeaf(origin, 0.0f, false));
    float* data = leaf->buffer().data();
    auto& mask = leaf->getValueMask();
    bool any = false;
    for (int i = 0; i < kDim; ++i) {
        uint64_t word = 0;  // voxels (i, j, l) for all j, l: one 64-bit word of the mask
        for (int j = 0; j < kDim; ++j) {
            const float* row = rows + (i * kColumnWidth + j) * kColumnRowStride;
            std::memcpy(data + (i << 6) + (j << 3), row, kDim * sizeof(float));
            for (int l = 0; l < kDim; ++l) word |= uint64_t(row[l] > 0.0f) << ((j << 3) + l);
        }
        mask.template getWord<uint64_t>(openvdb::Index(i)) = word;
        any |= word != 0;
    }
    return any ? leaf.release() : nullptr;
}

/// Fills the density leaves of a range of columns from the particles whose support overlaps
/// them (a gather over columns, a scatter over each particle's clipped sphere inside the
/// column): no two tasks write the same memory, and each voxel sums its particles in the
/// index's fixed order, which does not depend on the box queried, so the values are the
/// same for any grouping and any thread count.
struct RasterizeColumnOp
{
    const ParticleIndex& particles;
    const std::vector<openvdb::Coord>& origins;
    const std::vector<size_t>& order;
    const std::vector<Column>& columns;
    std::vector<FloatLeaf*>& results;
    double voxelSize;
    double effectiveRadius;
    CancelPoll& poll;
    std::atomic<size_t>& done;
    bool avx2;  ///< run the AVX2 copy of the loop (InstructionSet.h)
    tbb::enumerable_thread_specific<std::vector<float>>& columnScratch;  ///< per thread

    void operator()(const tbb::blocked_range<size_t>& range) const
    {
#if NONBLOPPY_HAS_AVX2_COPY
        if (avx2) { fillColumnsAvx2(range); return; }
#endif
        fillColumns<false>(range);
    }

#if NONBLOPPY_HAS_AVX2_COPY
    /// fillColumns() compiled for AVX2, with every call in it inlined (flatten): the row
    /// function can only be inlined here, not into fillColumns<true>, which is compiled for
    /// the baseline before it is inlined. Called, it cost ~40% of the stage.
    NONBLOPPY_TARGET_AVX2 __attribute__((flatten)) void fillColumnsAvx2(const tbb::blocked_range<size_t>& range) const
    {
        fillColumns<true>(range);
    }
#endif

    /// The columns of @a range. Always inlined, so that each caller compiles it for its own
    /// instruction set.
    template<bool Avx2>
    __attribute__((always_inline)) inline void fillColumns(const tbb::blocked_range<size_t>& range) const
    {
        const auto& positions = particles.sortedPositions();
        auto accessor = particles.impl().grid->getConstAccessor();
        const float h = float(voxelSize);
        const float invH = 1.0f / h;
        const float radius = float(effectiveRadius);
        const float radius2 = radius * radius;
        const float minDistance2 = (kMinDistanceFraction * radius) * (kMinDistanceFraction * radius);
        constexpr int kDim = int(FloatLeaf::DIM);
        // The column's sums, rows of kColumnRowStride floats along z, one per (x, y): on the
        // heap, once per thread (a few hundred KB, too much for a caller's thread stack).
        std::vector<float>& scratch = columnScratch.local();
        scratch.resize(size_t(kColumnWidth) * kColumnWidth * kColumnRowStride);
        float* const values = scratch.data();
        std::vector<std::pair<uint32_t, uint32_t>> runs;  // particle slots [first, end)
        size_t leavesSincePoll = 0;

        for (size_t c = range.begin(); c < range.end(); ++c) {
            const Column& column = columns[c];
            if (leavesSincePoll >= kLeavesPerPoll) {
                leavesSincePoll = 0;
                if (poll.stopped()) return;
            }
            leavesSincePoll += column.end - column.first;
            const auto [columnX, columnY] = columnOf(origins[order[column.first]]);
            const openvdb::Coord origin(columnX, columnY, origins[order[column.first]][2]);
            const int height = origins[order[column.end - 1]][2] + kDim - origin[2];  // voxels in z
            // The voxels filled, relative to the origin: [boxFirst, boxLast] per axis, the box of
            // the column's stacks. Isolated droplets make columns of one or two stacks; with
            // the whole column's 32 x 32 voxels queried and cleared, they took 30-50% more
            // rasterization time than one stack at a time (100,000 particles 40 r_e apart).
            int boxFirst[3] = {kColumnWidth, kColumnWidth, 0}, boxLast[3] = {-1, -1, height - 1};
            // Zeroed: the rows of the stacks the column holds. The others inside the box
            // only ever get +0 added (a voxel within r_e of a particle lies in a candidate
            // leaf, and the candidates of this column's cell and z-range are all in it) and
            // are never read, so they are left as they are.
            uint32_t stacksZeroed = 0;  // bit sx * kColumnStacks + sy
            for (size_t n = column.first; n < column.end; ++n) {
                const int sx = (origins[order[n]][0] - origin[0]) / kDim, sy = (origins[order[n]][1] - origin[1]) / kDim;
                const uint32_t bit = 1u << (sx * kColumnStacks + sy);
                if (stacksZeroed & bit) continue;
                stacksZeroed |= bit;
                boxFirst[0] = std::min(boxFirst[0], sx * kDim);
                boxFirst[1] = std::min(boxFirst[1], sy * kDim);
                boxLast[0] = std::max(boxLast[0], sx * kDim + kDim - 1);
                boxLast[1] = std::max(boxLast[1], sy * kDim + kDim - 1);
                for (int i = 0; i < kDim; ++i) {
                    for (int j = 0; j < kDim; ++j) {
                        const int row = (sx * kDim + i) * kColumnWidth + sy * kDim + j;
                        std::fill_n(values + row * kColumnRowStride, height + 8, 0.0f);
                    }
                }
            }
            const openvdb::Vec3d columnMin = (origin + openvdb::Coord(boxFirst[0], boxFirst[1], boxFirst[2])).asVec3d() * voxelSize;
            const openvdb::Vec3d columnMax = (origin + openvdb::Coord(boxLast[0], boxLast[1], boxLast[2])).asVec3d() * voxelSize;
            ZSpan span;
            // The runs are listed first and walked here rather than in a visitor lambda:
            // a lambda is compiled for the baseline, so the AVX2 row code would not inline.
            runs.clear();
            particle_index_internal::forEachRunInBox(particles.impl(), accessor,
                columnMin - openvdb::Vec3d(effectiveRadius), columnMax + openvdb::Vec3d(effectiveRadius),
                [&](uint32_t first, uint32_t end) { runs.emplace_back(first, end); });
            for (const auto& [first, end] : runs) {
                for (uint32_t k = first; k < end; ++k) {
                    const openvdb::Vec3f& p = positions[k];
                    // Voxel range of the particle's support, relative to the column origin.
                    int lo[3], hi[3];
                    bool empty = false;
                    for (int a = 0; a < 3; ++a) {
                        lo[a] = ceilToInt((p[a] - radius) * invH) - origin[a];
                        hi[a] = floorToInt((p[a] + radius) * invH) - origin[a];
                        empty |= std::max(boxFirst[a], lo[a]) > std::min(boxLast[a], hi[a]);
                    }
                    if (empty) continue;
                    // The z-vectors: lanes from the first voxel in the column; lanes outside
                    // the support's range [lo, hi] get +∞ (the same voxels in either copy).
                    const int zFirst = std::max(0, lo[2]), zLast = std::min(height - 1, hi[2]);
                    span.count = 0;
                    for (int start = zFirst; start <= zLast; start += 8) {
                        const int v = span.count++;
                        span.start[v] = start;
                        for (int l = 0; l < 8; ++l) {
                            const int z = start + l;
                            // Distance from the voxel's own leaf origin, as leaf by leaf.
                            const float pz = p[2] - float(origin[2] + (z & ~(kDim - 1))) * h;
                            const float dz = float(z & (kDim - 1)) * h - pz;
                            span.dz2[v][l] = (z >= lo[2] && z <= hi[2]) ? dz * dz
                                                                        : std::numeric_limits<float>::infinity();
                        }
                    }
                    for (int i = std::max(boxFirst[0], lo[0]); i <= std::min(boxLast[0], hi[0]); ++i) {
                        const float dx = float(origin[0] + i) * h - p[0];
                        for (int j = std::max(boxFirst[1], lo[1]); j <= std::min(boxLast[1], hi[1]); ++j) {
                            const float dy = float(origin[1] + j) * h - p[1];
                            // A row outside the support's disc gets an infinite distance, so
                            // its weights are r_e/∞ − 1 < 0, clamped to +0, which adds
                            // nothing: cheaper than skipping it, since the skip is a branch
                            // taken at random twice per i (about 20 mispredictions per
                            // particle and column; the stage measured 10% faster without).
                            const float rowDistance2 = dx * dx + dy * dy;
                            const float dxy2 =
                                rowDistance2 < radius2 ? rowDistance2 : std::numeric_limits<float>::infinity();
                            float* row = values + (i * kColumnWidth + j) * kColumnRowStride;
                            for (int v = 0; v < span.count; ++v) {
#if NONBLOPPY_HAS_AVX2_COPY
                                if constexpr (Avx2) {
                                    addRowVectorAvx2(row + span.start[v], span.dz2[v], dxy2,
                                                     radius, minDistance2);
                                    continue;
                                }
#endif
                                addRowVector(row + span.start[v], span.dz2[v], dxy2, radius,
                                             minDistance2);
                            }
                        }
                    }
                }
            }
            for (size_t n = column.first; n < column.end; ++n) {
                const openvdb::Coord& leafOrigin = origins[order[n]];
                const int row = (leafOrigin[0] - origin[0]) * kColumnWidth + (leafOrigin[1] - origin[1]);
                results[order[n]] = makeLeaf(leafOrigin, values + row * kColumnRowStride + (leafOrigin[2] - origin[2]));
            }
        }
        // Progress for the caller's display; a stop is remembered by the poll.
        const size_t leaves = columns[range.end() - 1].end - columns[range.begin()].first;
        const size_t finished = done.fetch_add(leaves) + leaves;
        poll.stopped(int(100.0 * double(finished) / double(origins.size())));
    }
};

} // namespace

void surface_stages_internal::requireVoxelsPerRadius(double effectiveRadius, double voxelSize, const LengthNames& names)
{
    if (effectiveRadius / voxelSize > kMaxVoxelsPerRadius) {
        std::ostringstream msg;
        msg << names.voxelSize << " " << voxelSize << " is too small for " << names.radius << " " << effectiveRadius
            << ": at most "
            << kMaxVoxelsPerRadius << " voxels per radius";
        throw ParameterError(msg.str());
    }
}

openvdb::FloatGrid::Ptr rasterizeDensity(const ParticleIndex& particles, const DensitySettings& settings,
                                         openvdb::util::NullInterrupter* interrupter)
{
    return instruction_set_internal::rasterizeDensity(particles, settings, interrupter,
                                                      instruction_set_internal::InstructionSet::Auto);
}

openvdb::FloatGrid::Ptr instruction_set_internal::rasterizeDensity(const ParticleIndex& particles,
                                                                   const DensitySettings& settings,
                                                                   openvdb::util::NullInterrupter* interrupter,
                                                                   InstructionSet set)
{
    openvdb::initialize();
    parameter_checks_internal::requirePositive(settings.effectiveRadius, "--radius");
    parameter_checks_internal::requireRadiusBelowMaximum(settings.effectiveRadius);
    openvdb::math::Transform::Ptr transform = settings.transform;
    if (!transform) {
        parameter_checks_internal::requirePositive(settings.voxelSize, "--voxel-size");
        openvdb_scale_internal::requireOpenVdbScale(settings.voxelSize, kMinCellSize, "--voxel-size");
        transform = openvdb::math::Transform::createLinearTransform(settings.voxelSize);
    } else {
        if (transform->baseMap()->type() != openvdb::math::UniformScaleMap::mapType()) {
            throw ParameterError("rasterizeDensity needs a uniform-scale transform without translation or rotation");
        }
        // OpenVDB makes a transform of any scale (API review).
        openvdb_scale_internal::requireOpenVdbScale(transform->voxelSize()[0], kMinCellSize, "--voxel-size");
    }
    const double voxelSize = transform->voxelSize()[0];
    surface_stages_internal::requireVoxelsPerRadius(settings.effectiveRadius, voxelSize);
    particle_index_internal::requireCellsPerRadius(particles, settings.effectiveRadius);

    const cancellation_internal::AnnouncedStage announced(interrupter, "rasterize density");
    CancelPoll poll(interrupter, "rasterize density");
    const std::vector<openvdb::Coord> origins =
        candidateLeafOrigins(particles, *transform, settings.effectiveRadius, poll);
    std::vector<FloatLeaf*> results(origins.size(), nullptr);
    std::atomic<size_t> done{0};
    if (!poll.stopped()) {
        std::vector<size_t> order;
        const std::vector<Column> columns = groupColumns(origins, order);
        tbb::enumerable_thread_specific<std::vector<float>> columnScratch;
        tbb::parallel_for(tbb::blocked_range<size_t>(0, columns.size(), 4),
            RasterizeColumnOp{particles, origins, order, columns, results, voxelSize, settings.effectiveRadius, poll,
                              done, instruction_set_internal::useAvx2(set), columnScratch});
    }

    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0.0f);
    grid->setTransform(transform);
    grid->setName("density");
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    openvdb::FloatTree& tree = grid->tree();
    // Leaves not yet in the tree are ours to delete; those added belong to the grid.
    // Through an accessor: consecutive origins mostly share their parent node, which it
    // keeps, where Tree::addLeaf() descends from the root each time (64x benchmark input,
    // 84,537 leaves: 13-15 ms -> 10-11 ms, the rest mostly the parents' first-touch faults).
    openvdb::tree::ValueAccessor<openvdb::FloatTree> accessor(tree);
    for (size_t n = 0; n < results.size(); ++n) {
        if (poll.stoppedAt(n)) {
            for (size_t m = n; m < results.size(); ++m) delete results[m];
            break;
        }
        if (results[n]) accessor.addLeaf(results[n]);
    }
    poll.throwIfStopped();
    return grid;
}

} // namespace nonbloppy
