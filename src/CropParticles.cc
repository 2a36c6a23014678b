// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/CropParticles.h>

#include <nonbloppy/Error.h>

#include "FileFormats.h"
#include "NumberText.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstring>
#include <vector>

namespace nonbloppy {
namespace {

/// Particles per block: each block is counted, then copied, by one task, so the kept
/// particles land in their order whatever the threads.
constexpr size_t kBlockParticles = 65536;

bool inside(const openvdb::Vec3f& p, const openvdb::BBoxd& box)
{
    for (int axis = 0; axis < 3; ++axis) {
        // Written so that NaN fails both comparisons and is left out.
        if (!(double(p[axis]) >= box.min()[axis] && double(p[axis]) <= box.max()[axis])) return false;
    }
    return true;
}

} // namespace

void checkParticleBox(const openvdb::BBoxd& box)
{
    using number_text_internal::sixDigits;
    static const char* const kAxes[] = {"x", "y", "z"};
    for (int axis = 0; axis < 3; ++axis) {
        for (const auto& [name, value] : {std::pair<const char*, double>{"minimum", box.min()[axis]},
                                          std::pair<const char*, double>{"maximum", box.max()[axis]}}) {
            if (!std::isfinite(value)) {
                throw ParameterError(std::string("particle box: its ") + name + " " + kAxes[axis] + " is " +
                                     sixDigits(value) + ", not a finite number");
            }
        }
        if (box.min()[axis] > box.max()[axis]) {
            const auto [low, high] = number_text_internal::numbersApart(box.min()[axis], box.max()[axis]);
            throw ParameterError(std::string("particle box: its minimum ") + kAxes[axis] + " " + low +
                                 " exceeds its maximum " + high);
        }
    }
}

ParticleSet cropParticles(const ParticleSet& particles, const openvdb::BBoxd& box)
{
    checkParticleBox(box);
    io_internal::requireOneValuePerParticle(particles);
    const size_t count = particles.size();
    // Bytes per particle of each attribute.
    std::vector<size_t> valueBytes;
    for (const ParticleAttribute& a : particles.attributes) valueBytes.push_back(scalarSize(a.type) * size_t(a.components));
    // Pass 1: how many each block keeps; then where each block's particles go.
    const size_t blocks = (count + kBlockParticles - 1) / kBlockParticles;
    std::vector<size_t> firstKept(blocks + 1, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t block = range.begin(); block != range.end(); ++block) {
            const size_t end = std::min(count, (block + 1) * kBlockParticles);
            size_t kept = 0;
            for (size_t n = block * kBlockParticles; n < end; ++n) kept += inside(particles.positions[n], box);
            firstKept[block + 1] = kept;
        }
    });
    for (size_t block = 0; block < blocks; ++block) firstKept[block + 1] += firstKept[block];

    ParticleSet cropped;
    cropped.skipped = particles.skipped;
    cropped.positions.resize(firstKept[blocks]);
    cropped.attributes.resize(particles.attributes.size());
    for (size_t a = 0; a < particles.attributes.size(); ++a) {
        const ParticleAttribute& from = particles.attributes[a];
        ParticleAttribute& to = cropped.attributes[a];
        to.name = from.name;
        to.type = from.type;
        to.components = from.components;
        to.bytes.resize(firstKept[blocks] * valueBytes[a]);
    }
    // Pass 2: each block copies what it keeps into its own range.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t block = range.begin(); block != range.end(); ++block) {
            const size_t end = std::min(count, (block + 1) * kBlockParticles);
            size_t to = firstKept[block];
            for (size_t n = block * kBlockParticles; n < end; ++n) {
                if (!inside(particles.positions[n], box)) continue;
                cropped.positions[to] = particles.positions[n];
                for (size_t a = 0; a < valueBytes.size(); ++a) {
                    std::memcpy(cropped.attributes[a].bytes.data() + to * valueBytes[a],
                                particles.attributes[a].bytes.data() + n * valueBytes[a], valueBytes[a]);
                }
                ++to;
            }
        }
    });
    return cropped;
}

} // namespace nonbloppy
