// SPDX-License-Identifier: Apache-2.0
/// @file InterpolateAttributes.cc
/// @brief Kernel-weighted particle attributes at mesh vertices, through the particle index.

#include "Cancellation.h"
#include "FileFormats.h"
#include "ParameterChecks.h"
#include "ParticleIndexImpl.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/InterpolateAttributes.h>
#include <nonbloppy/Kernel.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <cmath>
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

/// One attribute's values in the index's sorted order, so the inner loop streams.
struct SortedAttribute
{
    int components = 1;
    /// Integers name or count things (ids, flags, material indices), and a mean of two ids
    /// is neither: they take the nearest particle's value instead, exactly.
    bool nearest = false;
    std::vector<double> values;     ///< sorted slot × components, unless nearest
    std::vector<int64_t> integers;  ///< sorted slot × components, if nearest
};

/// Fill the attribute values of a range of vertices.
struct InterpolateOp
{
    const SurfaceMesh& mesh;
    const ParticleIndex::Impl& index;
    const std::vector<SortedAttribute>& attributes;
    std::vector<MeshAttribute>& out;
    int meanComponents;   ///< components of the attributes that are means
    bool anyNearest;      ///< whether some attribute takes the nearest particle's value
    float effectiveRadius;
    cancellation_internal::CancelPoll& poll;

    static constexpr uint32_t kNone = ~uint32_t(0);

    void operator()(const tbb::blocked_range<size_t>& range) const
    {
        if (poll.stopped()) return;
        openvdb::tree::ValueAccessor<const particle_index_internal::IndexTree> accessor(index.grid->tree());
        const std::vector<openvdb::Vec3f>& positions = index.sortedPositions;
        std::vector<double> sums(static_cast<size_t>(meanComponents));
        std::vector<uint32_t> inside;       // the vertex's particles within r_e, in the query's order
        std::vector<float> insideDistance;  // their squared distances
        std::vector<float> insideWeight;    // their weights
        const double r = effectiveRadius;
        const float radiusSqr = effectiveRadius * effectiveRadius;
        // mpsWeightSquared()'s floor on the squared distance, computed as it computes it.
        const float minDistance = kMinDistanceFraction * effectiveRadius;
        const float minDistanceSqr = minDistance * minDistance;
#if defined(__SSE2__)
        const __m128 limit = _mm_set1_ps(radiusSqr), floorSqr = _mm_set1_ps(minDistanceSqr);
        const __m128 radius = _mm_set1_ps(effectiveRadius), one = _mm_set1_ps(1.0f);
#else
        (void)minDistanceSqr;
#endif
        for (size_t i = range.begin(); i < range.end(); ++i) {
            const openvdb::Vec3f v = mesh.points[i];
#if defined(__SSE2__)
            const __m128 vx = _mm_set1_ps(v[0]), vy = _mm_set1_ps(v[1]), vz = _mm_set1_ps(v[2]);
#endif
            std::fill(sums.begin(), sums.end(), 0.0);
            double weightSum = 0.0;
            // The nearest particle with a weight: smallest squared distance, then smallest
            // index in the input (so neither the index's order nor the threads decide).
            float nearestDistanceSqr = 0.0f;
            uint32_t nearest = kNone;
            // First the particles within r_e, in the query's order, listed without a branch
            // (stored, then kept by advancing the count): about one candidate in six is, at
            // random, and a branch on it mispredicted every other time.
            size_t count = 0;
            particle_index_internal::forEachRunInBox(index, accessor,
                openvdb::Vec3d(v) - openvdb::Vec3d(r), openvdb::Vec3d(v) + openvdb::Vec3d(r),
                [&](uint32_t first, uint32_t end) {
                    if (inside.size() < count + (end - first) + 4) {
                        inside.resize(2 * (count + (end - first) + 4));
                        insideDistance.resize(inside.size());
                        insideWeight.resize(inside.size());
                    }
                    uint32_t k = first;
#if defined(__SSE2__)
                    // Four at a time: lengthSqr()'s float operations in its order, so the
                    // same distances. x, y, z of four Vec3f (12 packed floats a, b, c) into a
                    // register each.
                    for (; k + 4 <= end; k += 4) {
                        const float* p = positions[k].asPointer();
                        const __m128 a = _mm_loadu_ps(p), b = _mm_loadu_ps(p + 4), c = _mm_loadu_ps(p + 8);
                        const __m128 x = _mm_shuffle_ps(_mm_shuffle_ps(a, a, _MM_SHUFFLE(3, 3, 3, 0)),
                                                        _mm_shuffle_ps(b, c, _MM_SHUFFLE(1, 1, 2, 2)), _MM_SHUFFLE(2, 0, 1, 0));
                        const __m128 y = _mm_shuffle_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(0, 0, 1, 1)),
                                                        _mm_shuffle_ps(b, c, _MM_SHUFFLE(2, 2, 3, 3)), _MM_SHUFFLE(2, 0, 2, 0));
                        const __m128 z = _mm_shuffle_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(1, 1, 2, 2)),
                                                        _mm_shuffle_ps(c, c, _MM_SHUFFLE(3, 3, 0, 0)), _MM_SHUFFLE(2, 0, 2, 0));
                        const __m128 dx = _mm_sub_ps(vx, x), dy = _mm_sub_ps(vy, y), dz = _mm_sub_ps(vz, z);
                        const __m128 d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
                        const int within = _mm_movemask_ps(_mm_cmplt_ps(d2, limit));
                        alignas(16) float distances[4];
                        _mm_store_ps(distances, d2);
                        for (int l = 0; l < 4; ++l) {
                            inside[count] = k + uint32_t(l);
                            insideDistance[count] = distances[l];
                            count += size_t((within >> l) & 1);
                        }
                    }
#endif
                    for (; k < end; ++k) {
                        const float distanceSqr = (v - positions[k]).lengthSqr();
                        inside[count] = k;
                        insideDistance[count] = distanceSqr;
                        count += distanceSqr < radiusSqr;
                    }
                });
            // Their weights, mpsWeightSquared()'s operations four at a time (IEEE square roots
            // and divisions: the same bits), ahead of the sums: one by one, each sum waited
            // for its square root and division.
            size_t n = 0;
#if defined(__SSE2__)
            for (; n + 4 <= count; n += 4) {
                const __m128 clamped = _mm_max_ps(_mm_loadu_ps(insideDistance.data() + n), floorSqr);
                _mm_storeu_ps(insideWeight.data() + n, _mm_sub_ps(_mm_div_ps(radius, _mm_sqrt_ps(clamped)), one));
            }
#endif
            for (; n < count; ++n) insideWeight[n] = mpsWeightSquared(insideDistance[n], effectiveRadius);
            for (n = 0; n < count; ++n) {
                const uint32_t k = inside[n];
                const float distanceSqr = insideDistance[n];
                const float w = insideWeight[n];
                if (w == 0.0f) continue;
                weightSum += w;
                if (anyNearest && (nearest == kNone || distanceSqr < nearestDistanceSqr
                    || (distanceSqr == nearestDistanceSqr && index.originalIndex[k] < index.originalIndex[nearest]))) {
                    nearestDistanceSqr = distanceSqr;
                    nearest = k;
                }
                size_t s = 0;
                for (const SortedAttribute& a : attributes) {
                    if (a.nearest) continue;
                    const double* value = a.values.data() + size_t(k) * size_t(a.components);
                    for (int c = 0; c < a.components; ++c) sums[s++] += double(w) * value[c];
                }
            }
            // No particle within r_e (weightSum 0): the values stay the zeros they were made.
            if (weightSum == 0.0) continue;
            size_t s = 0;
            for (size_t a = 0; a < attributes.size(); ++a) {
                const SortedAttribute& attribute = attributes[a];
                const size_t components = size_t(attribute.components);
                if (attribute.nearest) {
                    std::copy_n(attribute.integers.data() + size_t(nearest) * components, components,
                                out[a].integers.data() + i * components);
                    continue;
                }
                float* dst = out[a].values.data() + i * components;
                for (size_t c = 0; c < components; ++c) dst[c] = float(sums[s++] / weightSum);
            }
        }
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
        const ParticleIndex particleIndex = ParticleIndex::build(particles.positions, effectiveRadius);
        const ParticleIndex::Impl& index = particleIndex.impl();
        std::vector<SortedAttribute> sorted(attributes.size());
        int meanComponents = 0;
        bool anyNearest = false;
        for (size_t a = 0; a < attributes.size(); ++a) {
            const ParticleAttribute& attribute = *attributes[a];
            const size_t components = size_t(attribute.components);
            SortedAttribute& to = sorted[a];
            to.components = attribute.components;
            to.nearest = out[a].integer;
            if (to.nearest) {
                to.integers.resize(particles.size() * components);
                anyNearest = true;
            } else {
                to.values.resize(particles.size() * components);
                meanComponents += attribute.components;
            }
            const std::vector<uint32_t>& original = index.originalIndex;
            const size_t width = scalarSize(attribute.type);
            tbb::parallel_for(tbb::blocked_range<size_t>(0, original.size()),
                [&](const tbb::blocked_range<size_t>& range) {
                    for (size_t k = range.begin(); k < range.end(); ++k) {
                        for (size_t c = 0; c < components; ++c) {
                            const size_t from = size_t(original[k]) * components + c;
                            if (to.nearest) {  // exact: a uint64 past int64 was refused above
                                io_internal::integerValue(attribute.bytes.data() + from * width, attribute.type,
                                                          to.integers[k * components + c]);
                            } else {
                                to.values[k * components + c] = attribute.asDouble(original[k], int(c));
                            }
                        }
                    }
                });
        }
        tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.points.size(), 256),
            InterpolateOp{mesh, index, sorted, out, meanComponents, anyNearest, float(effectiveRadius), poll});
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
