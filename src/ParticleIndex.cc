// SPDX-License-Identifier: Apache-2.0
#include "Cancellation.h"
#include "OpenVdbScale.h"
#include "ParticleIndexImpl.h"

#include <nonbloppy/Error.h>

#include <openvdb/tree/LeafManager.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <cmath>
#include <limits>
#include <sstream>

namespace nonbloppy {

namespace {

/// PointArray over a plain vector, as OpenVDB's partitioner wants it.
struct PositionList
{
    using PosType = openvdb::Vec3R;
    const std::vector<openvdb::Vec3f>& positions;
    size_t size() const { return positions.size(); }
    void getPos(size_t n, openvdb::Vec3R& xyz) const { xyz = positions[n]; }
};

/// Index of the first non-finite position, or size() if all are finite (unspecified after a
/// stop of @a poll).
size_t firstNonFinite(const std::vector<openvdb::Vec3f>& positions, cancellation_internal::CancelPoll& poll)
{
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, positions.size()), positions.size(),
        [&](const tbb::blocked_range<size_t>& range, size_t found) {
            for (size_t n = range.begin(); n < range.end() && n < found; ++n) {
                if (poll.stoppedAt(n - range.begin())) return found;
                const openvdb::Vec3f& p = positions[n];
                if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) return n;
            }
            return found;
        },
        [](size_t a, size_t b) { return std::min(a, b); });
}

} // namespace

ParticleIndex::ParticleIndex() : mImpl(new Impl) {}
ParticleIndex::~ParticleIndex() = default;
ParticleIndex::ParticleIndex(ParticleIndex&&) noexcept = default;
ParticleIndex& ParticleIndex::operator=(ParticleIndex&&) noexcept = default;

size_t ParticleIndex::size() const { return mImpl->sortedPositions.size(); }
const std::vector<openvdb::Vec3f>& ParticleIndex::sortedPositions() const { return mImpl->sortedPositions; }
const std::vector<uint32_t>& ParticleIndex::originalIndex() const { return mImpl->originalIndex; }
double ParticleIndex::cellSize() const { return mImpl->cellSize; }
openvdb::GridBase::ConstPtr ParticleIndex::indexGrid() const { return mImpl->grid; }

ParticleIndex ParticleIndex::build(std::vector<openvdb::Vec3f> positions, double cellSize,
                                   openvdb::util::NullInterrupter* interrupter)
{
    using namespace particle_index_internal;
    openvdb::initialize();
    if (!(cellSize > 0.0) || !std::isfinite(cellSize)) {
        std::ostringstream msg;
        msg << "particle index cell size must be > 0, got " << cellSize;
        throw ParameterError(msg.str());
    }
    openvdb_scale_internal::requireOpenVdbScale(cellSize, kMinCellSize, "particle index cell size");
    if (positions.size() > size_t(std::numeric_limits<uint32_t>::max())) {
        throw ParameterError("too many particles: at most 4294967295 are supported");
    }
    cancellation_internal::CancelPoll poll(interrupter, "index particles");
    const size_t bad = firstNonFinite(positions, poll);
    poll.throwIfStopped();
    if (bad < positions.size()) {
        std::ostringstream msg;
        msg << "non-finite position of particle " << bad;
        throw ParameterError(msg.str());
    }
    // Index coordinates are 32-bit: refuse positions whose cell number would overflow.
    double maxAbs = 0.0;
    for (size_t n = 0; n < positions.size(); ++n) {
        if (poll.stoppedAt(n)) poll.throwIfStopped();
        const openvdb::Vec3f& p = positions[n];
        maxAbs = std::max({maxAbs, double(std::abs(p[0])), double(std::abs(p[1])), double(std::abs(p[2]))});
    }
    if (maxAbs / cellSize > 1.0e9) {
        std::ostringstream msg;
        msg << "particle coordinates up to " << maxAbs << " are too far from the origin for a cell size of "
            << cellSize << " (32-bit index space)";
        throw ParameterError(msg.str());
    }

    ParticleIndex index;
    Impl& impl = *index.mImpl;
    impl.cellSize = cellSize;
    const openvdb::math::Transform::Ptr transform = openvdb::math::Transform::createLinearTransform(cellSize);
    // OpenVDB's partitioner takes no interrupter, and stopping its TBB context would leave
    // its own serial steps working on partial counts: it runs to the end.
    impl.grid = openvdb::tools::createPointIndexGrid<openvdb::tools::PointIndexGrid>(
        PositionList{positions}, *transform);
    poll.throwIfStopped();

    // Give every particle a sorted slot: leaves in tree order, then voxels in offset order,
    // then (sorted here, so the result never depends on the partitioner's threading)
    // ascending original index. Afterwards the grid's index lists hold slots, not originals.
    openvdb::tree::LeafManager<IndexTree> leaves(impl.grid->tree());
    std::vector<size_t> leafStart(leaves.leafCount() + 1, 0);
    for (size_t n = 0; n < leaves.leafCount(); ++n) {
        leafStart[n + 1] = leafStart[n] + leaves.leaf(n).indices().size();
    }
    impl.sortedPositions.resize(positions.size());
    impl.originalIndex.resize(positions.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.leafCount()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t n = range.begin(); n < range.end(); ++n) {
                if (poll.stopped()) return;  // a leaf holds up to a few thousand particles
                IndexLeaf& leaf = leaves.leaf(n);
                auto& indices = leaf.indices();
                uint32_t begin = 0;
                for (openvdb::Index offset = 0; offset < IndexLeaf::SIZE; ++offset) {
                    const uint32_t end = uint32_t(leaf.getValue(offset));
                    std::sort(indices.begin() + begin, indices.begin() + end);
                    begin = end;
                }
                for (size_t i = 0; i < indices.size(); ++i) {
                    const size_t slot = leafStart[n] + i;
                    impl.originalIndex[slot] = uint32_t(indices[i]);
                    impl.sortedPositions[slot] = positions[uint32_t(indices[i])];
                    indices[i] = openvdb::PointIndex32(uint32_t(slot));
                }
            }
        });
    poll.throwIfStopped();
    return index;
}

} // namespace nonbloppy
