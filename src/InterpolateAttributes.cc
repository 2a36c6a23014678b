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
                });
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
