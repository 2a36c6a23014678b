// SPDX-License-Identifier: Apache-2.0
/// @file InterpolateAttributes.cc
/// @brief Kernel-weighted particle attributes at mesh vertices, through the particle index.

#include "Cancellation.h"
#include "FileFormats.h"
#include "ParameterChecks.h"
#include "ParticleIndexImpl.h"
#include "VertexGroups.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/InterpolateAttributes.h>
#include <nonbloppy/Kernel.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <cmath>
#include <cstring>
#include <sstream>

namespace nonbloppy {

std::vector<std::string>
resolveAttributeNames(const ParticleSet& particles, const std::vector<std::string>& requested)
{
    std::vector<std::string> names;
    if (requested.size() == 1 && requested[0] == "all") {
        for (const ParticleAttribute& attribute : particles.attributes) names.push_back(attribute.name);
        return names;
    }
    for (const std::string& name : requested) {
        if (!particles.findAttribute(name)) {
            std::string have;
            for (const ParticleAttribute& attribute : particles.attributes) {
                have += (have.empty() ? "" : ", ") + attribute.name;
            }
            throw ParameterError("unknown attribute '" + name + "'; the particles have" +
                                 (have.empty() ? " no attributes" : ": " + have));
        }
        if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
    }
    return names;
}

namespace {

/// Edge of the cells vertices are grouped by, and of the particle index's cells, over r_e.
/// 64x benchmark input with the dam-break frame's id and velocity, interpolation at two
/// threads (two runs each): groups of 1.5 r_e over cells of r_e 0.37 s; groups of 1, 2 and
/// 3 r_e 0.37, 0.39 and 0.46 s; cells of r_e/2 (groups 1, 1.5, 2 r_e) 0.41-0.43 s.
constexpr double kGroupOverRadius = 1.5;
constexpr double kIndexCellOverRadius = 1.0;

/// The attribute values the interpolation reads.
struct AttributeValues
{
    /// Every mean component of a particle side by side, attribute after attribute
    /// (meanComponents doubles per particle), in the index's sorted order, so that a vertex's
    /// particles (neighbours in that order) share cache lines.
    std::vector<double> means;
    int meanComponents = 0;
    /// Per attribute that takes the nearest particle's value (integers: ids, flags, material
    /// indices, whose mean would name nothing), its components per particle in input order
    /// (one particle is read per vertex); empty for a mean attribute.
    std::vector<std::vector<int64_t>> integers;
    bool anyNearest = false;
};

/// Candidates are tested four at a time (SSE2).
constexpr size_t kLanes = 4;
/// Vertex groups of a task between two polls.
constexpr size_t kGroupsPerPoll = 16;

/// The particles of a vertex group's box grown by r_e, with their slots.
using Candidates = vertex_groups_internal::GroupCandidates<kLanes, /*kWithSlots=*/true>;

/// Fill the attribute values of the vertices of a range of vertex groups. Each group
/// gathers the particles within r_e of its vertices' box once; each vertex then lists
/// those within r_e of itself. They come in the order of a search of its own (cells in x,
/// y, z order, a cell's particles in slot order), so its sums are the same bits as if it
/// had searched alone, whatever the groups.
struct InterpolateGroupsOp
{
    const SurfaceMesh& mesh;
    const ParticleIndex::Impl& index;
    const memory_internal::UnwrittenVector<uint32_t>& vertexOrder;  ///< vertices sorted by group
    const std::vector<size_t>& groupStart;  ///< groups of vertexOrder, plus the end
    const AttributeValues& values;
    std::vector<MeshAttribute>& out;  ///< sized, zeros; out[a].integer for a nearest value
    float effectiveRadius;
    cancellation_internal::CancelPoll& poll;

    void operator()(const tbb::blocked_range<size_t>& range) const
    {
        openvdb::tree::ValueAccessor<const particle_index_internal::IndexTree> accessor(index.grid->tree());
        const std::vector<openvdb::Vec3f>& positions = index.sortedPositions;
        Candidates candidates;
        std::vector<double> sums(static_cast<size_t>(values.meanComponents));
        std::vector<uint32_t> inside;       // the vertex's particles within r_e, in search order
        std::vector<float> insideDistance;  // their squared distances
        std::vector<float> insideWeight;    // their weights
        const float radius = effectiveRadius;
        const float radiusSqr = radius * radius;
        // mpsWeightSquared()'s floor on the squared distance, computed as it computes it.
        const float minDistance = kMinDistanceFraction * radius;
        const float minDistanceSqr = minDistance * minDistance;
        for (size_t g = range.begin(); g < range.end(); ++g) {
            if ((g - range.begin()) % kGroupsPerPoll == 0 && poll.stopped()) return;
            const size_t begin = groupStart[g], end = groupStart[g + 1];
            // The box of the group's vertices, grown by a hair so that float rounding of the
            // box distances never drops a particle a vertex on its face can reach.
            openvdb::Vec3f vertexMin = mesh.points[vertexOrder[begin]], vertexMax = vertexMin;
            for (size_t n = begin + 1; n < end; ++n) {
                vertexMin = openvdb::math::minComponent(vertexMin, mesh.points[vertexOrder[n]]);
                vertexMax = openvdb::math::maxComponent(vertexMax, mesh.points[vertexOrder[n]]);
            }
            const float slack = 1e-4f * float(index.cellSize);
            const openvdb::Vec3f boxMin = vertexMin - openvdb::Vec3f(slack);
            const openvdb::Vec3f boxMax = vertexMax + openvdb::Vec3f(slack);
            candidates.clear();
            particle_index_internal::forEachRunInBox(index, accessor,
                openvdb::Vec3d(boxMin) - openvdb::Vec3d(radius), openvdb::Vec3d(boxMax) + openvdb::Vec3d(radius),
                [&](uint32_t first, uint32_t last) {
                    candidates.gather(positions, first, last, boxMin, boxMax, radiusSqr);
                });
            candidates.pad(boxMax[0] + 4.0f * radius);
            if (inside.size() < candidates.count) {
                inside.resize(candidates.count);
                insideDistance.resize(candidates.count);
                insideWeight.resize(candidates.count);
            }
            for (size_t n = begin; n < end; ++n) {
                const size_t i = vertexOrder[n];
                const size_t count = listInside(mesh.points[i], candidates, radiusSqr, inside, insideDistance);
                weigh(count, insideDistance, insideWeight, minDistanceSqr);
                accumulate(i, count, inside.data(), insideDistance.data(), insideWeight.data(), sums.data());
            }
        }
    }

    /// The candidates within r_e of @a v into @a inside (slots) and @a insideDistance
    /// (squared distances, lengthSqr()'s float operations in its order), in candidate order;
    /// returns their count. Four at a time, listed without a branch (stored, then kept by
    /// advancing the count): about one candidate in six is, at random, and a branch on it
    /// mispredicted every other time.
    static size_t listInside(const openvdb::Vec3f& v, const Candidates& candidates, float radiusSqr,
                             std::vector<uint32_t>& inside, std::vector<float>& insideDistance)
    {
        const float* cx = candidates.x.data();
        const float* cy = candidates.y.data();
        const float* cz = candidates.z.data();
        const uint32_t* slots = candidates.slots.data();
        uint32_t* insideSlot = inside.data();
        float* distance = insideDistance.data();
        size_t count = 0;
#if defined(__SSE2__)
        const __m128 vx = _mm_set1_ps(v[0]), vy = _mm_set1_ps(v[1]), vz = _mm_set1_ps(v[2]);
        const __m128 limit = _mm_set1_ps(radiusSqr);
        for (size_t c = 0; c < candidates.count; c += kLanes) {
            const __m128 dx = _mm_sub_ps(vx, _mm_loadu_ps(cx + c));
            const __m128 dy = _mm_sub_ps(vy, _mm_loadu_ps(cy + c));
            const __m128 dz = _mm_sub_ps(vz, _mm_loadu_ps(cz + c));
            const __m128 d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
            const int within = _mm_movemask_ps(_mm_cmplt_ps(d2, limit));
            alignas(16) float distances[kLanes];
            _mm_store_ps(distances, d2);
            for (size_t l = 0; l < kLanes; ++l) {
                insideSlot[count] = slots[c + l];
                distance[count] = distances[l];
                count += size_t((within >> l) & 1);
            }
        }
#else
        for (size_t c = 0; c < candidates.count; ++c) {
            const float distanceSqr = (v - openvdb::Vec3f(cx[c], cy[c], cz[c])).lengthSqr();
            insideSlot[count] = slots[c];
            distance[count] = distanceSqr;
            count += distanceSqr < radiusSqr;
        }
#endif
        return count;
    }

    /// The weights of the first @a count particles of @a insideDistance, mpsWeightSquared()'s
    /// operations four at a time (IEEE square roots and divisions: the same bits), ahead of
    /// the sums: one by one, each sum waited for its square root and division.
    void weigh(size_t count, const std::vector<float>& insideDistance, std::vector<float>& insideWeight,
               float minDistanceSqr) const
    {
        size_t n = 0;
#if defined(__SSE2__)
        const __m128 floorSqr = _mm_set1_ps(minDistanceSqr);
        const __m128 radius = _mm_set1_ps(effectiveRadius), one = _mm_set1_ps(1.0f);
        for (; n + 4 <= count; n += 4) {
            const __m128 clamped = _mm_max_ps(_mm_loadu_ps(insideDistance.data() + n), floorSqr);
            _mm_storeu_ps(insideWeight.data() + n, _mm_sub_ps(_mm_div_ps(radius, _mm_sqrt_ps(clamped)), one));
        }
#else
        (void)minDistanceSqr;
#endif
        for (; n < count; ++n) insideWeight[n] = mpsWeightSquared(insideDistance[n], effectiveRadius);
    }

    /// Vertex @a i's values from its @a count particles within r_e (@a inside, their squared
    /// distances and weights): the weighted means, and the nearest particle's integers.
    void accumulate(size_t i, size_t count, const uint32_t* inside, const float* insideDistance,
                    const float* insideWeight, double* sums) const
    {
        double weightSum;
        switch (values.meanComponents) {  // sums held in registers where the count is known
        case 1: weightSum = sumMeans<1>(count, inside, insideWeight, sums); break;
        case 3: weightSum = sumMeans<3>(count, inside, insideWeight, sums); break;
        default: weightSum = sumMeans<0>(count, inside, insideWeight, sums); break;
        }
        // No particle within r_e (weightSum 0): the values stay the zeros they were made.
        if (weightSum == 0.0) return;
        const uint32_t nearest = values.anyNearest ? nearestOf(count, inside, insideDistance, insideWeight) : 0;
        size_t s = 0;
        for (size_t a = 0; a < out.size(); ++a) {
            const size_t components = size_t(out[a].components);
            if (out[a].integer) {
                std::copy_n(values.integers[a].data() + size_t(nearest) * components, components,
                            out[a].integers.data() + i * components);
                continue;
            }
            float* dst = out[a].values.data() + i * components;
            for (size_t c = 0; c < components; ++c) dst[c] = float(sums[s++] / weightSum);
        }
    }

    /// Σ w f over the @a count particles @a inside with weights @a weight, per mean
    /// component (kComponents of them, or values.meanComponents for 0), into @a sums; returns
    /// Σ w. In double, in list order: the result does not depend on the thread count.
    template<int kComponents>
    double sumMeans(size_t count, const uint32_t* inside, const float* weight, double* sums) const
    {
        const size_t components = size_t(kComponents > 0 ? kComponents : values.meanComponents);
        double registers[kComponents > 0 ? kComponents : 1] = {};
        double* total = kComponents > 0 ? registers : sums;
        std::fill(total, total + components, 0.0);
        double weightSum = 0.0;
        for (size_t n = 0; n < count; ++n) {
            const float w = weight[n];
            if (w == 0.0f) continue;  // at r_e, rounded: no weight (0 × an infinite value is NaN)
            weightSum += w;
            const double* value = values.means.data() + size_t(inside[n]) * components;
            for (size_t c = 0; c < components; ++c) total[c] += double(w) * value[c];
        }
        if (kComponents > 0) std::copy_n(total, components, sums);
        return weightSum;
    }

    /// The input index of the nearest of the @a count particles @a inside with a weight:
    /// smallest squared distance, then smallest index in the input (so neither the index's
    /// order nor the threads decide). One key per particle, the distance's bits (non-negative
    /// floats order as their bits) above the index, and the smallest kept, without a branch:
    /// which particle is nearest so far changes at random along the list.
    uint32_t nearestOf(size_t count, const uint32_t* inside, const float* distance, const float* weight) const
    {
        uint64_t best = ~uint64_t(0);
        for (size_t n = 0; n < count; ++n) {
            uint32_t bits;
            std::memcpy(&bits, distance + n, sizeof(bits));
            const uint64_t key = (uint64_t(bits) << 32) | index.originalIndex[inside[n]];
            best = std::min(best, weight[n] != 0.0f ? key : ~uint64_t(0));
        }
        return uint32_t(best);  // only asked when some particle has a weight
    }
};

} // namespace

std::vector<const ParticleAttribute*>
checkAttributes(const ParticleSet& particles, const std::vector<std::string>& names)
{
    std::vector<const ParticleAttribute*> attributes;
    for (const std::string& name : resolveAttributeNames(particles, names)) {
        const ParticleAttribute& attribute = *particles.findAttribute(name);
        io_internal::requireCountableValues(attribute);
        if (attribute.size() != particles.size()) {
            throw ParameterError("attribute '" + attribute.name + "' has " +
                                 std::to_string(attribute.size()) + " values for " +
                                 std::to_string(particles.size()) + " particles");
        }
        io_internal::requireInt64Values(attribute, "a mesh attribute holds");
        attributes.push_back(&attribute);
    }
    return attributes;
}

void
interpolateAttributes(SurfaceMesh& mesh, const ParticleSet& particles,
                      const std::vector<std::string>& names, double effectiveRadius,
                      openvdb::util::NullInterrupter* interrupter)
{
    parameter_checks_internal::requirePositive(effectiveRadius, "--radius");
    parameter_checks_internal::requireRadiusBelowMaximum(effectiveRadius);
    // Every check before start(), so that a start() is always followed by its end().
    const std::vector<const ParticleAttribute*> attributes = checkAttributes(particles, names);

    std::vector<MeshAttribute> out(attributes.size());
    for (size_t a = 0; a < attributes.size(); ++a) {
        out[a].name = attributes[a]->name;
        out[a].components = attributes[a]->components;
        out[a].integer = isIntegerType(attributes[a]->type);
        const size_t count = mesh.points.size() * size_t(attributes[a]->components);
        if (out[a].integer) out[a].integers.resize(count);  // zeros
        else out[a].values.resize(count);
    }
    if (!attributes.empty() && !mesh.points.empty()) {
        const cancellation_internal::AnnouncedStage announced(interrupter, "interpolate attributes");
        cancellation_internal::CancelPoll poll(interrupter, "interpolate attributes");
        // The index sorts the particles into cells of r_e: a vertex's support spans 3³ cells.
        const ParticleIndex particleIndex = ParticleIndex::build(particles.positions, kIndexCellOverRadius * effectiveRadius);
        const ParticleIndex::Impl& index = particleIndex.impl();
        const std::vector<uint32_t>& original = index.originalIndex;
        AttributeValues values;
        values.integers.resize(attributes.size());
        for (size_t a = 0; a < attributes.size(); ++a) {
            if (out[a].integer) values.anyNearest = true;
            else values.meanComponents += attributes[a]->components;
        }
        values.means.resize(particles.size() * size_t(values.meanComponents));
        int meanOffset = 0;  // of attribute a's first component in a particle's means
        for (size_t a = 0; a < attributes.size(); ++a) {
            const ParticleAttribute& attribute = *attributes[a];
            const size_t components = size_t(attribute.components);
            if (out[a].integer) {
                // In input order: one value is read per vertex, through the input index.
                std::vector<int64_t>& to = values.integers[a];
                to.resize(particles.size() * components);
                const size_t width = scalarSize(attribute.type);
                tbb::parallel_for(tbb::blocked_range<size_t>(0, to.size()),
                    [&](const tbb::blocked_range<size_t>& range) {
                        for (size_t n = range.begin(); n < range.end(); ++n) {
                            // exact: a uint64 past int64 was refused above
                            io_internal::integerValue(attribute.bytes.data() + n * width, attribute.type, to[n]);
                        }
                    });
                continue;
            }
            const size_t stride = size_t(values.meanComponents);
            tbb::parallel_for(tbb::blocked_range<size_t>(0, original.size()),
                [&](const tbb::blocked_range<size_t>& range) {
                    for (size_t k = range.begin(); k < range.end(); ++k) {
                        double* to = values.means.data() + k * stride + size_t(meanOffset);
                        for (size_t c = 0; c < components; ++c) to[c] = attribute.asDouble(original[k], int(c));
                    }
                });
            meanOffset += attribute.components;
        }
        memory_internal::UnwrittenVector<uint32_t> order;
        std::vector<size_t> groupStart;
        vertex_groups_internal::groupVerticesByCell(mesh.points, kGroupOverRadius * effectiveRadius, order,
                                                    groupStart, poll);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, groupStart.size() - 1, 64),
            InterpolateGroupsOp{mesh, index, order, groupStart, values, out, float(effectiveRadius), poll});
        poll.throwIfStopped();
    }

    for (MeshAttribute& attribute : out) {
        auto same = std::find_if(mesh.attributes.begin(), mesh.attributes.end(),
                                 [&](const MeshAttribute& m) { return m.name == attribute.name; });
        if (same != mesh.attributes.end()) *same = std::move(attribute);
        else mesh.attributes.push_back(std::move(attribute));
    }
}

} // namespace nonbloppy
