// SPDX-License-Identifier: Apache-2.0
#include "Cancellation.h"
#include "InstructionSet.h"
#include "ParameterChecks.h"
#include "ParticleIndexImpl.h"
#include "UnwrittenVector.h"
#include "VertexGroups.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/Kernel.h>
#include <nonbloppy/RelaxVertices.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
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

/// The particles within r_e of a vertex group's box, in x, y, z arrays.
using CandidateBuffer = vertex_groups_internal::GroupCandidates<kLanes, /*kWithSlots=*/false>;

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
    vertex_groups_internal::groupVerticesByCell(mesh.points, kGroupCells * particles.cellSize(), order, groupStart, poll);
    std::atomic<size_t> groupsDone{0};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, groupStart.size() - 1, 64),
        RelaxGroupsOp{particles, order, groupStart, mesh.points, settings.iterations,
                      float(settings.effectiveRadius), float(settings.blend), float(maxStep), poll,
                      groupsDone, avx2});
    poll.throwIfStopped();
}

} // namespace nonbloppy
