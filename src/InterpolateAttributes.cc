// SPDX-License-Identifier: Apache-2.0
/// @file InterpolateAttributes.cc
/// @brief Kernel-weighted particle attributes at mesh vertices, through the particle index.

#include "Cancellation.h"
#include "ParameterChecks.h"
#include "ParticleIndexImpl.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/InterpolateAttributes.h>
#include <nonbloppy/Kernel.h>

#include <tbb/parallel_for.h>

#include <algorithm>
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
    std::string name;
    int components = 1;
    /// Integers name or count things (ids, flags, material indices), and a mean of two ids
    /// is neither: they take the nearest particle's value instead.
    bool nearest = false;
    std::vector<double> values;  ///< sorted slot × components
};

/// Fill the attribute values of a range of vertices.
struct InterpolateOp
{
    const SurfaceMesh& mesh;
    const ParticleIndex::Impl& index;
    const std::vector<SortedAttribute>& attributes;
    std::vector<MeshAttribute>& out;
    int totalComponents;
    float effectiveRadius;
    cancellation_internal::CancelPoll& poll;

    static constexpr uint32_t kNone = ~uint32_t(0);

    void operator()(const tbb::blocked_range<size_t>& range) const
    {
        if (poll.stopped()) return;
        openvdb::tree::ValueAccessor<const particle_index_internal::IndexTree> accessor(index.grid->tree());
        const std::vector<openvdb::Vec3f>& positions = index.sortedPositions;
        std::vector<double> sums(static_cast<size_t>(totalComponents));
        const double r = effectiveRadius;
        for (size_t i = range.begin(); i < range.end(); ++i) {
            const openvdb::Vec3f v = mesh.points[i];
            std::fill(sums.begin(), sums.end(), 0.0);
            double weightSum = 0.0;
            // The nearest particle with a weight: smallest squared distance, then smallest
            // index in the input (so neither the index's order nor the threads decide).
            float nearestDistanceSqr = 0.0f;
            uint32_t nearest = kNone;
            particle_index_internal::forEachRunInBox(index, accessor,
                openvdb::Vec3d(v) - openvdb::Vec3d(r), openvdb::Vec3d(v) + openvdb::Vec3d(r),
                [&](uint32_t first, uint32_t end) {
                    for (uint32_t k = first; k < end; ++k) {
                        const float distanceSqr = (v - positions[k]).lengthSqr();
                        const float w = mpsWeightSquared(distanceSqr, effectiveRadius);
                        if (w == 0.0f) continue;
                        weightSum += w;
                        if (nearest == kNone || distanceSqr < nearestDistanceSqr
                            || (distanceSqr == nearestDistanceSqr && index.originalIndex[k] < index.originalIndex[nearest])) {
                            nearestDistanceSqr = distanceSqr;
                            nearest = k;
                        }
                        size_t s = 0;
                        for (const SortedAttribute& a : attributes) {
                            if (a.nearest) {
                                s += size_t(a.components);
                                continue;
                            }
                            const double* value = a.values.data() + size_t(k) * size_t(a.components);
                            for (int c = 0; c < a.components; ++c) sums[s++] += double(w) * value[c];
                        }
                    }
                });
            size_t s = 0;
            for (size_t a = 0; a < attributes.size(); ++a) {
                const SortedAttribute& attribute = attributes[a];
                float* dst = out[a].values.data() + i * size_t(attribute.components);
                for (int c = 0; c < attribute.components; ++c, ++s) {
                    if (nearest == kNone) {
                        dst[c] = 0.0f;
                    } else if (attribute.nearest) {
                        dst[c] = float(attribute.values[size_t(nearest) * size_t(attribute.components) + size_t(c)]);
                    } else {
                        dst[c] = float(sums[s] / weightSum);
                    }
                }
            }
        }
    }
};

} // namespace

void
interpolateAttributes(SurfaceMesh& mesh, const ParticleSet& particles,
                      const std::vector<std::string>& names, double effectiveRadius,
                      openvdb::util::NullInterrupter* interrupter)
{
    parameter_checks_internal::requirePositive(effectiveRadius, "--radius");
    const std::vector<std::string> resolved = resolveAttributeNames(particles, names);
    // Every check before start(), so that a start() is always followed by its end().
    std::vector<const ParticleAttribute*> attributes;
    for (const std::string& name : resolved) {
        const ParticleAttribute& attribute = *particles.findAttribute(name);
        if (attribute.size() != particles.size()) {
            throw ParameterError("attribute '" + attribute.name + "' has " +
                                 std::to_string(attribute.size()) + " values for " +
                                 std::to_string(particles.size()) + " particles");
        }
        attributes.push_back(&attribute);
    }

    std::vector<MeshAttribute> out(attributes.size());
    for (size_t a = 0; a < attributes.size(); ++a) {
        out[a].name = attributes[a]->name;
        out[a].components = attributes[a]->components;
        out[a].integer = isIntegerType(attributes[a]->type);
        out[a].values.resize(mesh.points.size() * size_t(attributes[a]->components));  // zeros
    }
    if (!attributes.empty() && !mesh.points.empty()) {
        const cancellation_internal::AnnouncedStage announced(interrupter, "interpolate attributes");
        cancellation_internal::CancelPoll poll(interrupter, "interpolate attributes");
        // The index sorts the particles into cells of r_e: a vertex's support spans 3³ cells.
        const ParticleIndex particleIndex = ParticleIndex::build(particles.positions, effectiveRadius);
        const ParticleIndex::Impl& index = particleIndex.impl();
        std::vector<SortedAttribute> sorted(attributes.size());
        int totalComponents = 0;
        for (size_t a = 0; a < attributes.size(); ++a) {
            const ParticleAttribute& attribute = *attributes[a];
            sorted[a].name = attribute.name;
            sorted[a].components = attribute.components;
            sorted[a].nearest = out[a].integer;
            sorted[a].values.resize(particles.size() * size_t(attribute.components));
            totalComponents += attribute.components;
            const std::vector<uint32_t>& original = index.originalIndex;
            tbb::parallel_for(tbb::blocked_range<size_t>(0, original.size()),
                [&](const tbb::blocked_range<size_t>& range) {
                    for (size_t k = range.begin(); k < range.end(); ++k) {
                        for (int c = 0; c < attribute.components; ++c) {
                            sorted[a].values[k * size_t(attribute.components) + size_t(c)] =
                                attribute.asDouble(original[k], c);
                        }
                    }
                });
        }
        tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.points.size(), 256),
            InterpolateOp{mesh, index, sorted, out, totalComponents, float(effectiveRadius), poll});
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
