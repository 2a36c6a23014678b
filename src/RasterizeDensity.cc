// SPDX-License-Identifier: Apache-2.0
#include "Cancellation.h"
#include "InstructionSet.h"
#include "ParticleIndexImpl.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/Kernel.h>
#include <nonbloppy/RasterizeDensity.h>

#include <openvdb/tree/LeafManager.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <atomic>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if NONBLOPPY_HAS_AVX2_COPY
#include <immintrin.h>
#endif
#include <cmath>
#include <sstream>

namespace nonbloppy {

namespace {

using cancellation_internal::CancelPoll;
using FloatLeaf = openvdb::FloatTree::LeafNodeType;
using particle_index_internal::IndexLeaf;
using particle_index_internal::IndexTree;

/// Density leaves of a task between two polls: a leaf gathers every particle within r_e of
/// its 512 voxels, so a task of many leaves would otherwise run for milliseconds.
constexpr size_t kLeavesPerPoll = 8;

/// Origins of the density leaves that may hold a voxel within r_e of a particle: for each
/// leaf of the particle index, the density leaves overlapping its active cells' bounding box
/// grown by r_e. Sorted, so the leaf order (and thus everything after) is deterministic.
/// On a stop (@a poll) the list is incomplete; the caller checks.
std::vector<openvdb::Coord> candidateLeafOrigins(const ParticleIndex& particles,
                                                 const openvdb::math::Transform& transform,
                                                 double effectiveRadius, CancelPoll& poll)
{
    const IndexTree& indexTree = particles.impl().grid->tree();
    const double cellSize = particles.cellSize();
    openvdb::tree::LeafManager<const IndexTree> leaves(indexTree);
    tbb::enumerable_thread_specific<std::vector<openvdb::Coord>> perThread;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.leafCount()),
        [&](const tbb::blocked_range<size_t>& range) {
            std::vector<openvdb::Coord>& origins = perThread.local();
            for (size_t n = range.begin(); n < range.end(); ++n) {
                if (poll.stoppedAt(64 * (n - range.begin()))) return;  // every 64 index leaves
                openvdb::CoordBBox cells;
                leaves.leaf(n).evalActiveBoundingBox(cells, /*visitVoxels=*/true);
                const openvdb::Vec3d worldMin = (cells.min().asVec3d() - 0.5) * cellSize - effectiveRadius;
                const openvdb::Vec3d worldMax = (cells.max().asVec3d() + 0.5) * cellSize + effectiveRadius;
                const openvdb::Vec3d indexMin = transform.worldToIndex(worldMin);
                const openvdb::Vec3d indexMax = transform.worldToIndex(worldMax);
                const openvdb::Coord lo(openvdb::Coord::ceil(indexMin) & ~int(FloatLeaf::DIM - 1));
                const openvdb::Coord hi(openvdb::Coord::floor(indexMax) & ~int(FloatLeaf::DIM - 1));
                openvdb::Coord origin;
                for (origin[0] = lo[0]; origin[0] <= hi[0]; origin[0] += FloatLeaf::DIM)
                    for (origin[1] = lo[1]; origin[1] <= hi[1]; origin[1] += FloatLeaf::DIM)
                        for (origin[2] = lo[2]; origin[2] <= hi[2]; origin[2] += FloatLeaf::DIM)
                            origins.push_back(origin);
            }
        });
    std::vector<openvdb::Coord> all;
    if (poll.stopped()) return all;
    for (auto& origins : perThread) all.insert(all.end(), origins.begin(), origins.end());
    // Coord's < is a total order, so the parallel sort gives std::sort's result; it can be
    // stopped (hundreds of thousands of origins, tens of ms).
    cancellation_internal::runStoppable(poll, [&] { tbb::parallel_sort(all.begin(), all.end()); });
    if (poll.stopped()) return all;
    all.erase(std::unique(all.begin(), all.end()), all.end());
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

/// Add the weights of one particle to voxels zFirst..zLast (rounded out to groups of 4) of a
/// leaf row: voxel l is at squared distance dxy2 + (l·h − pz)². re/d − 1 ≤ 0 from d = r_e on, so clamping at 0 cuts the
/// support without a branch. SSE and scalar paths give identical bits (IEEE sqrt and div).
inline void addRowWeights(float* row, int zFirst, int zLast, float dxy2, float pz, float h, float radius,
                          float minDistance2)
{
#if defined(__SSE2__)
    const __m128 vh = _mm_set1_ps(h), vpz = _mm_set1_ps(pz), vdxy2 = _mm_set1_ps(dxy2);
    const __m128 vradius = _mm_set1_ps(radius), vmin = _mm_set1_ps(minDistance2);
    const __m128 one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps();
    // Only the 4-voxel halves the support reaches (a particle's 9-voxel span usually
    // straddles two leaves, so one half is often idle).
    for (int half = zFirst >> 2; half <= (zLast >> 2); ++half) {
        const __m128 lz = _mm_set_ps(float(4 * half + 3), float(4 * half + 2), float(4 * half + 1), float(4 * half));
        const __m128 dz = _mm_sub_ps(_mm_mul_ps(lz, vh), vpz);
        const __m128 d2 = _mm_add_ps(vdxy2, _mm_mul_ps(dz, dz));
        __m128 w = _mm_sub_ps(_mm_div_ps(vradius, _mm_sqrt_ps(_mm_max_ps(d2, vmin))), one);
        w = _mm_max_ps(w, zero);
        _mm_storeu_ps(row + 4 * half, _mm_add_ps(_mm_loadu_ps(row + 4 * half), w));
    }
#else
    for (int l = zFirst & ~3; l <= (zLast | 3); ++l) {
        const float dz = float(l) * h - pz;
        const float d2 = dxy2 + dz * dz;
        const float w = radius / std::sqrt(std::max(d2, minDistance2)) - 1.0f;
        row[l] += w > 0.0f ? w : 0.0f;
    }
#endif
}

#if NONBLOPPY_HAS_AVX2_COPY
/// addRowWeights() for the AVX2 copy of the loop (InstructionSet.h): the whole 8-voxel row
/// in one register. Voxels beyond the support get w = +0, which leaves their sums as they
/// are, so the bits are those of the baseline, which skips them.
NONBLOPPY_TARGET_AVX2 inline void addRowWeightsAvx2(float* row, float dxy2, float pz, float h, float radius,
                                                    float minDistance2)
{
    const __m256 lz = _mm256_set_ps(7.0f, 6.0f, 5.0f, 4.0f, 3.0f, 2.0f, 1.0f, 0.0f);
    const __m256 dz = _mm256_sub_ps(_mm256_mul_ps(lz, _mm256_set1_ps(h)), _mm256_set1_ps(pz));
    const __m256 d2 = _mm256_add_ps(_mm256_set1_ps(dxy2), _mm256_mul_ps(dz, dz));
    const __m256 distance = _mm256_sqrt_ps(_mm256_max_ps(d2, _mm256_set1_ps(minDistance2)));
    __m256 w = _mm256_sub_ps(_mm256_div_ps(_mm256_set1_ps(radius), distance), _mm256_set1_ps(1.0f));
    w = _mm256_max_ps(w, _mm256_setzero_ps());
    _mm256_storeu_ps(row, _mm256_add_ps(_mm256_loadu_ps(row), w));
}
#endif

/// Fills one density leaf from the particles whose support overlaps it (a gather over
/// leaves, a scatter over each particle's clipped sphere inside the leaf): no two tasks
/// write the same memory, and each voxel sums its particles in the index's fixed order.
struct RasterizeLeafOp
{
    const ParticleIndex& particles;
    const std::vector<openvdb::Coord>& origins;
    std::vector<FloatLeaf*>& results;
    double voxelSize;
    double effectiveRadius;
    CancelPoll& poll;
    std::atomic<size_t>& done;
    bool avx2;  ///< run the AVX2 copy of the loop (InstructionSet.h)

    void operator()(const tbb::blocked_range<size_t>& range) const
    {
#if NONBLOPPY_HAS_AVX2_COPY
        if (avx2) { fillLeavesAvx2(range); return; }
#endif
        fillLeaves<false>(range);
    }

#if NONBLOPPY_HAS_AVX2_COPY
    /// fillLeaves() compiled for AVX2 (it is inlined here).
    NONBLOPPY_TARGET_AVX2 void fillLeavesAvx2(const tbb::blocked_range<size_t>& range) const
    {
        fillLeaves<true>(range);
    }
#endif

    /// The leaves of @a range. Always inlined, so that each caller compiles it for its own
    /// instruction set.
    template<bool Avx2>
    __attribute__((always_inline)) inline void fillLeaves(const tbb::blocked_range<size_t>& range) const
    {
        const auto& positions = particles.sortedPositions();
        auto accessor = particles.impl().grid->getConstAccessor();
        const float h = float(voxelSize);
        const float invH = 1.0f / h;
        const float radius = float(effectiveRadius);
        const float radius2 = radius * radius;
        const float minDistance2 = (kMinDistanceFraction * radius) * (kMinDistanceFraction * radius);
        constexpr int kDim = int(FloatLeaf::DIM);
        float values[FloatLeaf::SIZE];

        for (size_t n = range.begin(); n < range.end(); ++n) {
            if ((n - range.begin()) % kLeavesPerPoll == 0 && poll.stopped()) return;
            const openvdb::Coord origin = origins[n];
            std::fill(values, values + FloatLeaf::SIZE, 0.0f);
            const openvdb::Vec3d leafMin = origin.asVec3d() * voxelSize;
            const openvdb::Vec3d leafMax = (origin.asVec3d() + double(kDim - 1)) * voxelSize;
            bool any = false;
            particle_index_internal::forEachRunInBox(accessor, particles.cellSize(),
                leafMin - openvdb::Vec3d(effectiveRadius), leafMax + openvdb::Vec3d(effectiveRadius),
                [&](uint32_t first, uint32_t end) {
                    for (uint32_t k = first; k < end; ++k) {
                        const openvdb::Vec3f& p = positions[k];
                        // Voxel range of the particle's support, relative to the leaf origin.
                        int lo[3], hi[3];
                        bool empty = false;
                        for (int a = 0; a < 3; ++a) {
                            lo[a] = std::max(0, ceilToInt((p[a] - radius) * invH) - origin[a]);
                            hi[a] = std::min(kDim - 1, floorToInt((p[a] + radius) * invH) - origin[a]);
                            empty |= lo[a] > hi[a];
                        }
                        if (empty) continue;
                        any = true;
                        const float pz = p[2] - float(origin[2]) * h;
                        for (int i = lo[0]; i <= hi[0]; ++i) {
                            const float dx = float(origin[0] + i) * h - p[0];
                            for (int j = lo[1]; j <= hi[1]; ++j) {
                                const float dy = float(origin[1] + j) * h - p[1];
                                const float dxy2 = dx * dx + dy * dy;
                                if (!(dxy2 < radius2)) continue;
                                // Every group of 4 voxels of the row that the particle's
                                // z-range reaches: branch-free SIMD, voxels outside get 0.
                                // (Clipping each row to its chord was tried: mispredicted
                                // trip counts made it slower.)
#if NONBLOPPY_HAS_AVX2_COPY
                                if constexpr (Avx2) {
                                    addRowWeightsAvx2(values + (i << 6) + (j << 3), dxy2, pz, h, radius,
                                                      minDistance2);
                                    continue;
                                }
#endif
                                addRowWeights(values + (i << 6) + (j << 3), lo[2], hi[2], dxy2, pz, h, radius,
                                              minDistance2);
                            }
                        }
                    }
                });
            if (!any) { results[n] = nullptr; continue; }
            auto* leaf = new FloatLeaf(origin, 0.0f, false);
            bool active = false;
            for (openvdb::Index i = 0; i < FloatLeaf::SIZE; ++i) {
                if (values[i] > 0.0f) { leaf->setValueOn(i, values[i]); active = true; }
            }
            if (!active) { delete leaf; leaf = nullptr; }
            results[n] = leaf;
        }
        // Progress for the caller's display; a stop is remembered by the poll.
        const size_t finished = done.fetch_add(range.size()) + range.size();
        poll.stopped(int(100.0 * double(finished) / double(origins.size())));
    }
};

} // namespace

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
    if (!(settings.effectiveRadius > 0.0) || !std::isfinite(settings.effectiveRadius)) {
        std::ostringstream msg;
        msg << "--radius must be > 0, got " << settings.effectiveRadius;
        throw ParameterError(msg.str());
    }
    openvdb::math::Transform::Ptr transform = settings.transform;
    if (!transform) {
        if (!(settings.voxelSize > 0.0) || !std::isfinite(settings.voxelSize)) {
            std::ostringstream msg;
            msg << "--voxel-size must be > 0, got " << settings.voxelSize;
            throw ParameterError(msg.str());
        }
        transform = openvdb::math::Transform::createLinearTransform(settings.voxelSize);
    } else if (transform->baseMap()->type() != openvdb::math::UniformScaleMap::mapType()) {
        throw ParameterError("rasterizeDensity needs a uniform-scale transform without translation or rotation");
    }
    const double voxelSize = transform->voxelSize()[0];

    if (interrupter) interrupter->start("rasterize density");
    CancelPoll poll(interrupter, "rasterize density");
    const std::vector<openvdb::Coord> origins =
        candidateLeafOrigins(particles, *transform, settings.effectiveRadius, poll);
    std::vector<FloatLeaf*> results(origins.size(), nullptr);
    std::atomic<size_t> done{0};
    if (!poll.stopped()) {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, origins.size(), 16),
            RasterizeLeafOp{particles, origins, results, voxelSize, settings.effectiveRadius, poll, done,
                            instruction_set_internal::useAvx2(set)});
    }

    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0.0f);
    grid->setTransform(transform);
    grid->setName("density");
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    openvdb::FloatTree& tree = grid->tree();
    // Leaves not yet in the tree are ours to delete; those added belong to the grid.
    for (size_t n = 0; n < results.size(); ++n) {
        if (poll.stoppedAt(n)) {
            for (size_t m = n; m < results.size(); ++m) delete results[m];
            break;
        }
        if (results[n]) tree.addLeaf(results[n]);
    }
    if (interrupter) interrupter->end();
    poll.throwIfStopped();
    return grid;
}

} // namespace nonbloppy
