// SPDX-License-Identifier: Apache-2.0
#include "Cancellation.h"
#include "OpenVdbScale.h"
#include "ParticleIndexImpl.h"

#include <nonbloppy/Error.h>

#include <openvdb/tree/LeafManager.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <tuple>

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

} // namespace

particle_index_internal::PositionScan
particle_index_internal::scanPositions(const std::vector<openvdb::Vec3f>& positions, cancellation_internal::CancelPoll& poll)
{
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, positions.size()), PositionScan{positions.size()},
        [&](const tbb::blocked_range<size_t>& range, PositionScan scan) {
            for (size_t n = range.begin(); n < range.end() && n < scan.firstNonFinite; ++n) {
                if (poll.stoppedAt(n - range.begin())) return scan;
                const openvdb::Vec3f& p = positions[n];
                if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
                    scan.firstNonFinite = n;
                    return scan;
                }
                scan.min = openvdb::math::minComponent(scan.min, p);
                scan.max = openvdb::math::maxComponent(scan.max, p);
            }
            return scan;
        },
        [](const PositionScan& a, const PositionScan& b) {
            // Positions past the first non-finite one do not count: each side only holds
            // positions before its own first, and a's range precedes b's.
            if (a.firstNonFinite < b.firstNonFinite) return a;
            PositionScan joined{b.firstNonFinite};
            joined.min = openvdb::math::minComponent(a.min, b.min);
            joined.max = openvdb::math::maxComponent(a.max, b.max);
            return joined;
        });
}

ParticleIndex::ParticleIndex() : mImpl(new Impl)
{
    // An empty grid of unit cells, not none: every function that takes an index (e.g.
    // SurfaceReconstructor::particleIndex() before its first frame) then works on it as on
    // build() of no particles, instead of dereferencing a null grid.
    mImpl->cellSize = 1.0;
    mImpl->grid = openvdb::tools::PointIndexGrid::create();
}
ParticleIndex::~ParticleIndex() = default;
ParticleIndex::ParticleIndex(ParticleIndex&&) noexcept = default;
ParticleIndex& ParticleIndex::operator=(ParticleIndex&&) noexcept = default;

size_t ParticleIndex::size() const { return mImpl->sortedPositions.size(); }
const std::vector<openvdb::Vec3f>& ParticleIndex::sortedPositions() const { return mImpl->sortedPositions; }
const std::vector<uint32_t>& ParticleIndex::originalIndex() const { return mImpl->originalIndex; }
double ParticleIndex::cellSize() const { return mImpl->cellSize; }
openvdb::BBoxd ParticleIndex::bounds() const { return mImpl->bounds; }
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
    // One parallel pass: the serial loop for the largest coordinate it replaced took 7 ms of
    // the 64x benchmark input's 0.09 s stage at two threads.
    const particle_index_internal::PositionScan scan = particle_index_internal::scanPositions(positions, poll);
    poll.throwIfStopped();
    if (scan.firstNonFinite < positions.size()) {
        throw ParameterError(particle_index_internal::nonFinitePositionMessage(scan.firstNonFinite));
    }
    // Index coordinates are 32-bit: refuse positions whose cell number would overflow.
    openvdb_scale_internal::requireIndexRange(double(scan.maxAbs()), cellSize, "particle", "cell size");

    ParticleIndex index;
    Impl& impl = *index.mImpl;
    impl.cellSize = cellSize;
    if (!positions.empty()) impl.bounds = openvdb::BBoxd(openvdb::Vec3d(scan.min), openvdb::Vec3d(scan.max));
    const openvdb::math::Transform::Ptr transform = openvdb::math::Transform::createLinearTransform(cellSize);
    // OpenVDB's partitioner takes no interrupter, and stopping its TBB context would leave
    // its own serial steps working on partial counts: it runs to the end. Its serial steps
    // leave a thread idle, which meanwhile allocates the sorted arrays: resize() zero-fills
    // them in one thread, 25 MB and 6,000 page faults on the 64x benchmark input.
    tbb::parallel_invoke(
        [&] {
            // Isolated: a std::bad_alloc of the other branch must not cancel its loops.
            cancellation_internal::runIsolatedFromCancellation([&] {
                impl.grid = openvdb::tools::createPointIndexGrid<openvdb::tools::PointIndexGrid>(
                    PositionList{positions}, *transform);
            });
        },
        [&] {
            impl.sortedPositions.resize(positions.size());
            impl.originalIndex.resize(positions.size());
        });
    poll.throwIfStopped();
    impl.grid->tree().evalLeafBoundingBox(impl.leafBounds);  // stays empty without particles

    // Give every particle a sorted slot: leaves in tree order, then voxels in offset order,
    // then (sorted here) by position, x, then y, then z, and ascending original index among
    // equal positions. So the slots, and every sum the stages make over them, depend neither
    // on the partitioner's threading nor on the particles' order in the file: a frame
    // written in another order (a conversion, a simulator that re-sorts its particles)
    // meshes to the same bytes. Afterwards the grid's index lists hold slots, not originals.
    openvdb::tree::LeafManager<IndexTree> leaves(impl.grid->tree());
    std::vector<size_t> leafStart(leaves.leafCount() + 1, 0);
    for (size_t n = 0; n < leaves.leafCount(); ++n) {
        leafStart[n + 1] = leafStart[n] + leaves.leaf(n).indices().size();
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.leafCount()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t n = range.begin(); n < range.end(); ++n) {
                if (poll.stopped()) return;  // a leaf holds up to a few thousand particles
                IndexLeaf& leaf = leaves.leaf(n);
                auto& indices = leaf.indices();
                uint32_t begin = 0;
                for (openvdb::Index offset = 0; offset < IndexLeaf::SIZE; ++offset) {
                    const uint32_t end = uint32_t(leaf.getValue(offset));
                    std::sort(indices.begin() + begin, indices.begin() + end,
                              [&](openvdb::PointIndex32 a, openvdb::PointIndex32 b) {
                                  const openvdb::Vec3f& p = positions[uint32_t(a)];
                                  const openvdb::Vec3f& q = positions[uint32_t(b)];
                                  return std::make_tuple(p[0], p[1], p[2], uint32_t(a))
                                       < std::make_tuple(q[0], q[1], q[2], uint32_t(b));
                              });
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
