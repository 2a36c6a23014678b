// SPDX-License-Identifier: Apache-2.0
/// @file ExtractSurface.cc
/// @brief Stage "extract surface". The only translation unit that includes
///        tools/VolumeToMesh.h (heavy to compile).
///
/// Large grids are meshed region by region (extractByRegion below): blocks of leaves (slabs,
/// cut again into bands where they hold many leaves), each handed to volumeToMesh with a
/// thin shell, then stitched exactly. That bounds the time
/// between two cancellation checks (volumeToMesh itself cannot be stopped) and lets every
/// region skip the leaves that no surface crossing touches.

#include <nonbloppy/Error.h>
#include <nonbloppy/ExtractSurface.h>

#include "Cancellation.h"
#include "NumberText.h"
#include "ParameterChecks.h"
#include "SurfaceStages.h"

#include <openvdb/tools/VolumeToMesh.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <utility>
#include <sstream>

#if defined(NONBLOPPY_LINK_OPENVDB_MESHER)
// Build option NONBLOPPY_LINK_OPENVDB_MESHER (CI's sanitizer build): call the mesher's
// operator() for FloatGrid that libopenvdb compiled (and exports) for its own volumeToMesh()
// instead of compiling ours, half this file's compile time there (130 s -> 66 s). Not the
// default: Debian builds it at -O2, and the stage took 13% longer with it (64x benchmark
// input, two threads, 0.61 -> 0.69 s, the same mesh).
extern template void openvdb::tools::VolumeToMesh::operator()<openvdb::FloatGrid>(const openvdb::FloatGrid&);
#endif

namespace nonbloppy {

namespace {

using FloatLeaf = openvdb::FloatTree::LeafNodeType;

/// @throw ParameterError unless @a threshold is finite and above @a background (the grid's
/// value outside its active voxels, which must count as outside: at or below it the surface
/// was empty, without a word) and @a adaptivity lies in [0,1].
void checkExtractParameters(double threshold, double adaptivity, double background)
{
    if (!std::isfinite(threshold)) {
        std::ostringstream msg;
        msg << "--threshold must be finite, got " << threshold;
        throw ParameterError(msg.str());
    }
    if (!(threshold > background)) {
        std::ostringstream msg;
        msg << "--threshold must lie above the density grid's background value " << background
            << " (its value outside the fluid), got " << number_text_internal::numberBeside(threshold, background);
        throw ParameterError(msg.str());
    }
    parameter_checks_internal::requireUnitInterval(adaptivity, "--adaptivity");
}

/// @throw ParameterError if @a density is classed as a level set: there the inside holds the
/// smaller values, and its surface would come out inside out (and tileDeepInterior() would
/// tile the outside).
template<typename GridT>
void requireDensityClass(const GridT& density, const char* function)
{
    if (density.getGridClass() == openvdb::GRID_LEVEL_SET) {
        throw ParameterError(std::string(function) + " needs a density grid (larger values inside), got the level set '" +
                             density.getName() + "' (smaller values inside): mesh it with openvdb::tools::volumeToMesh");
    }
}

/// Reverse every polygon of @a mesh. The density grows inwards, the opposite of a level set,
/// so volumeToMesh's polygons run clockwise seen from outside.
void orientOutwards(SurfaceMesh& mesh)
{
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.quads.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t n = range.begin(); n < range.end(); ++n) {
                const openvdb::Vec4I q = mesh.quads[n];
                mesh.quads[n] = openvdb::Vec4I(q[3], q[2], q[1], q[0]);
            }
        });
    for (openvdb::Vec3I& t : mesh.triangles) std::swap(t[0], t[2]);
}

/// volumeToMesh into @a mesh's vectors (it clears and resizes them, so they keep their
/// capacity), then every polygon reversed; normals and attributes cleared.
template<typename GridT>
void extractInto(const GridT& density, double threshold, double adaptivity, SurfaceMesh& mesh)
{
    checkExtractParameters(threshold, adaptivity, double(density.background()));
    openvdb::tools::volumeToMesh(density, mesh.points, mesh.triangles, mesh.quads, threshold, adaptivity);
    orientOutwards(mesh);
    mesh.normals.clear();
    mesh.attributes.clear();
}

// ---- Region by region -------------------------------------------------------------------
//
// volumeToMesh (adaptivity 0) puts one vertex (up to four in ambiguous cells) in every cell
// whose corners straddle the iso-value, at the mean of the crossings on the cell's edges, and
// one quad around every crossing edge, joining the four cells that share it. A cell's
// vertices depend on its eight corner values only, so any grid holding those corners yields
// bit-identical vertices for it (and for the signs of its neighbours, which settle its
// ambiguous faces). Hence a block of leaves can be meshed alone from a copy of its leaves
// plus kShellPlanes voxel planes beyond each cut face: each region keeps the quads whose
// centroid lies in it (both regions at a seam compute the same bits for a quad near it, so
// exactly one keeps it), and the vertices those quads share across a seam are welded by
// exact position. volumeToMesh's own surface mask would do the clipping too, but measured
// 20-30% slower: it rescans every crossing of the region.

/// How a leaf takes part in region-by-region extraction.
enum class LeafRole : uint8_t
{
    Kept,   ///< copied as it is: a crossing edge may touch one of its voxels
    Below,  ///< every value and every face-adjacent voxel below the iso-value: left out
    Above,  ///< every value and every face-adjacent voxel at or above it: an active tile
};

/// Whether all voxels that touch @a leaf across its face on @a axis, in direction @a dir
/// (±1), lie on the same side of @a iso as @a below says (a value outside any leaf: the tile
/// or background value there). Cost: up to 64 reads. Thread-safety: reads the tree only.
bool neighbourFaceIs(const openvdb::FloatTree& tree, const FloatLeaf& leaf, int axis, int dir,
                     bool below, float iso)
{
    openvdb::Coord origin = leaf.origin();
    origin[axis] += dir * int(FloatLeaf::DIM);
    const FloatLeaf* neighbour = tree.probeConstLeaf(origin);
    if (!neighbour) return (tree.getValue(origin) < iso) == below;
    const float* values = neighbour->buffer().data();
    openvdb::Coord local;
    local[axis] = dir > 0 ? 0 : int(FloatLeaf::DIM) - 1;
    for (int u = 0; u < int(FloatLeaf::DIM); ++u) {
        for (int v = 0; v < int(FloatLeaf::DIM); ++v) {
            local[(axis + 1) % 3] = u;
            local[(axis + 2) % 3] = v;
            if ((values[FloatLeaf::coordToOffset(local)] < iso) != below) return false;
        }
    }
    return true;
}

/// A leaf's role (see LeafRole): a leaf whose values all lie on one side of @a iso, as do
/// the voxels across its six faces, touches no crossing edge (edges join face neighbours),
/// so dropping it (below: the background, which must be below too) or turning it into a tile
/// (above) changes no crossing, no sign and therefore no vertex of the mesh.
LeafRole roleOf(const openvdb::FloatTree& tree, const FloatLeaf& leaf, float iso, float& minValue)
{
    const float* values = leaf.buffer().data();
    openvdb::Index below = 0;
    float low = values[0];
#if defined(__SSE2__)
    // Written out: GCC leaves the plain loop scalar (a compare, a setcc, an add and a minss
    // per value). collectPieces() in a one-thread profile of the 64x benchmark input: 1.78%
    // of the samples with the plain loop, 1.35% with this one.
    // _mm_min_ps(v, m) is (v < m ? v : m), std::min(m, v) lane by lane.
    const __m128 isoLanes = _mm_set1_ps(iso);
    __m128i belowLanes = _mm_setzero_si128();
    __m128 lowLanes = _mm_set1_ps(low);
    for (openvdb::Index i = 0; i < FloatLeaf::SIZE; i += 4) {
        const __m128 v = _mm_loadu_ps(values + i);
        belowLanes = _mm_sub_epi32(belowLanes, _mm_castps_si128(_mm_cmplt_ps(v, isoLanes)));
        lowLanes = _mm_min_ps(v, lowLanes);
    }
    alignas(16) uint32_t belowOf[4];
    alignas(16) float lowOf[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(belowOf), belowLanes);
    _mm_store_ps(lowOf, lowLanes);
    for (int l = 0; l < 4; ++l) {
        below += belowOf[l];
        low = std::min(low, lowOf[l]);
    }
#else
    for (openvdb::Index i = 0; i < FloatLeaf::SIZE; ++i) {
        below += values[i] < iso;
        low = std::min(low, values[i]);
    }
#endif
    minValue = low;
    const bool allBelow = below == FloatLeaf::SIZE;
    const bool allAbove = below == 0;
    if (!allBelow && !allAbove) return LeafRole::Kept;
    if (allBelow && !(tree.background() < iso)) return LeafRole::Kept;
    for (int axis = 0; axis < 3; ++axis) {
        for (int dir = -1; dir <= 1; dir += 2) {
            if (!neighbourFaceIs(tree, leaf, axis, dir, allBelow, iso)) return LeafRole::Kept;
        }
    }
    return allBelow ? LeafRole::Below : LeafRole::Above;
}

/// Turn off every voxel of @a leaf outside @a box and give it the value of the nearest voxel
/// inside (coordinates clamped to the box, axis by axis): a shell leaf of a region is cut
/// this way, and @a box must overlap the leaf. volumeToMesh looks at an edge only when one
/// of its two voxels is active, so the voxels beyond a cut add no crossing of their own:
/// filling them with the background instead made a false surface wherever the cut ran
/// through the fluid, meshed and then thrown away. On the 64x benchmark input that was a
/// quarter of the quads the regions made (3.10M made for 2.37M kept; 2.61M with this and
/// the shell's tiles made leaves, see meshRegion). Cost: O(512).
void cutToBox(FloatLeaf& leaf, const openvdb::CoordBBox& box)
{
    constexpr int kDim = int(FloatLeaf::DIM);
    const openvdb::Coord origin = leaf.origin();
    bool inside[3][kDim];
    int nearest[3][kDim];  // per axis, the leaf-local plane inside the box nearest to each plane
    for (int a = 0; a < 3; ++a) {
        // 64-bit: the box is unbounded (INT_MIN..INT_MAX) along the axis no cut crosses.
        const int low = int(std::max<int64_t>(0, int64_t(box.min()[a]) - origin[a]));
        const int high = int(std::min<int64_t>(kDim - 1, int64_t(box.max()[a]) - origin[a]));
        for (int l = 0; l < kDim; ++l) {
            inside[a][l] = low <= l && l <= high;
            nearest[a][l] = std::min(std::max(l, low), high);
        }
    }
    // A row (x, y) of 8 voxels along z keeps the bits of the z-planes inside the box.
    uint64_t zBits = 0;
    for (int z = 0; z < kDim; ++z) zBits |= uint64_t(inside[2][z]) << z;
    auto& mask = leaf.getValueMask();
    for (int x = 0; x < kDim; ++x) {
        uint64_t keepWord = 0;  // voxels (x, y, z) for all y, z: one word of the mask
        for (int y = 0; y < kDim; ++y) {
            if (inside[0][x] && inside[1][y]) keepWord |= zBits << (y * kDim);
        }
        mask.template getWord<uint64_t>(openvdb::Index(x)) &= keepWord;
    }
    // In place: a voxel inside the box is its own nearest, so no value read is overwritten.
    float* values = leaf.buffer().data();
    for (int x = 0; x < kDim; ++x) {
        for (int y = 0; y < kDim; ++y) {
            const float* from = values + (nearest[0][x] * kDim + nearest[1][y]) * kDim;
            float* to = values + (x * kDim + y) * kDim;
            for (int z = 0; z < kDim; ++z) to[z] = from[nearest[2][z]];
        }
    }
}

/// One leaf-sized piece of the grid: a leaf, or an active tile of leaf size.
struct Piece
{
    const FloatLeaf* leaf;  ///< null for a tile
    openvdb::Coord origin;
    LeafRole role;
    float value;            ///< the tile's value, or the leaf's smallest value
};

/// Bits of a vertex position, for welding by exact position.
struct PositionKey
{
    std::array<uint32_t, 3> bits;
    bool operator==(const PositionKey& other) const { return bits == other.bits; }
};

/// Vertex index by exact position, for the seam vertices of extractByRegionImpl(): open
/// addressing with linear probing in one array (a seam holds tens of thousands of vertices
/// per region, and std::unordered_map's node per entry cost a fifth of the extraction).
/// Cost: insert() and find() O(1) expected; clear() O(capacity), keeping the memory.
/// Thread-safety: find() from many threads at once while nobody inserts.
class SeamTable
{
public:
    static constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
    /// What find() gives for a position two vertices of one region had (see markAmbiguous()).
    static constexpr uint32_t kAmbiguous = kNone - 1;

    /// Remember @a index for @a key unless @a key is present; whether it was not.
    bool insert(const PositionKey& key, uint32_t index)
    {
        if (2 * (mSize + 1) > mSlots.size()) grow();
        if (!place(mSlots, key, index)) return false;
        ++mSize;
        return true;
    }
    /// Remember that two vertices had @a key: find() gives kAmbiguous for it from now on.
    void markAmbiguous(const PositionKey& key)
    {
        if (2 * (mSize + 1) > mSlots.size()) grow();
        Slot& slot = mSlots[slotOf(mSlots, key)];
        if (slot.index == kNone) ++mSize;
        slot.key = key;
        slot.index = kAmbiguous;
    }
    /// The index remembered for @a key, kAmbiguous, or kNone.
    uint32_t find(const PositionKey& key) const
    {
        return mSlots.empty() ? kNone : mSlots[slotOf(mSlots, key)].index;
    }
    void clear()
    {
        for (Slot& s : mSlots) s.index = kNone;
        mSize = 0;
    }
    void swap(SeamTable& other)
    {
        mSlots.swap(other.mSlots);
        std::swap(mSize, other.mSize);
    }

private:
    struct Slot
    {
        PositionKey key;
        uint32_t index = kNone;
    };
    static size_t hashOf(const PositionKey& key)
    {
        uint64_t h = 0x9E3779B97F4A7C15ull;
        for (uint32_t b : key.bits) h = (h ^ b) * 0x100000001B3ull;
        return size_t(h ^ (h >> 29));
    }
    /// The slot holding @a key, or the empty slot where it would go (@a slots is never full).
    static size_t slotOf(const std::vector<Slot>& slots, const PositionKey& key)
    {
        size_t slot = hashOf(key) & (slots.size() - 1);
        while (slots[slot].index != kNone && !(slots[slot].key == key)) slot = (slot + 1) & (slots.size() - 1);
        return slot;
    }
    /// Put @a key with @a index into @a slots unless it is there; whether it was put.
    static bool place(std::vector<Slot>& slots, const PositionKey& key, uint32_t index)
    {
        Slot& s = slots[slotOf(slots, key)];
        if (s.index != kNone) return false;
        s.key = key;
        s.index = index;
        return true;
    }
    void grow()
    {
        std::vector<Slot> larger(std::max<size_t>(1024, 2 * mSlots.size()));
        for (const Slot& s : mSlots) {
            if (s.index != kNone) place(larger, s.key, s.index);
        }
        mSlots.swap(larger);
    }

    std::vector<Slot> mSlots;  // a power of two, at most half full
    size_t mSize = 0;
};

PositionKey keyOf(const openvdb::Vec3s& p)
{
    PositionKey key;
    std::memcpy(key.bits.data(), p.asPointer(), sizeof(key.bits));
    return key;
}

/// All leaves and leaf-sized active tiles of @a tree, leaves with their roles (see LeafRole;
/// parallel over leaves, polling @a poll). Returns false when the tree holds larger active tiles (never so
/// for rasterizeDensity()'s grids); inactive tiles are taken to hold the background, as they
/// do there.
bool collectPieces(const openvdb::FloatTree& tree, float iso, std::vector<Piece>& pieces,
                   cancellation_internal::CancelPoll& poll)
{
    using Upper = openvdb::FloatTree::RootNodeType::ChildNodeType;
    using Lower = Upper::ChildNodeType;
    if (tree.root().cbeginValueOn()) return false;
    std::vector<const Upper*> uppers;
    tree.getNodes(uppers);
    for (const Upper* node : uppers) {
        if (node->cbeginValueOn()) return false;
    }
    std::vector<const FloatLeaf*> leaves;
    tree.getNodes(leaves);
    pieces.resize(leaves.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t n = range.begin(); n < range.end(); ++n) {
                if (poll.stoppedAt(n - range.begin())) return;
                Piece& piece = pieces[n];
                piece.leaf = leaves[n];
                piece.origin = leaves[n]->origin();
                piece.role = roleOf(tree, *leaves[n], iso, piece.value);
            }
        });
    poll.throwIfStopped();
    std::vector<const Lower*> lowers;
    tree.getNodes(lowers);
    for (const Lower* node : lowers) {
        for (auto tile = node->cbeginValueOn(); tile; ++tile) {
            pieces.push_back(Piece{nullptr, tile.getCoord(), LeafRole::Kept, *tile});
        }
    }
    return true;
}

/// Cuts of a row of leaf layers (along one axis) into ranges [first, last) that each hold
/// about @a leavesPerRegion kept leaves (@a keptPerLayer) and at least @a minLayers layers
/// (a last small remainder joins the range before it).
std::vector<std::pair<int, int>> slabsOf(const std::vector<int>& keptPerLayer, size_t leavesPerRegion,
                                         int minLayers)
{
    std::vector<std::pair<int, int>> slabs;
    int first = 0;
    size_t count = 0;
    for (int layer = 0; layer < int(keptPerLayer.size()); ++layer) {
        count += size_t(keptPerLayer[layer]);
        if (count >= leavesPerRegion && layer + 1 - first >= minLayers) {
            slabs.emplace_back(first, layer + 1);
            first = layer + 1;
            count = 0;
        }
    }
    if (first < int(keptPerLayer.size())) {
        if (!slabs.empty() && count < leavesPerRegion / 2) slabs.back().second = int(keptPerLayer.size());
        else slabs.emplace_back(first, int(keptPerLayer.size()));
    }
    return slabs;
}

/// Planes of voxels a region's shell keeps beyond each cut face. A quad claimed by a region
/// has its centroid in the region, so its cells lie at most two voxels below a face or
/// one above it, and their corners at most two planes out either side; volumeToMesh also
/// resolves a cell's ambiguous face from the signs of the cell across it, one plane further
/// (correctCellSigns in tools/VolumeToMesh.h), hence three. The voxels beyond are turned
/// off (cutToBox()); whatever crossings the cut still makes give quads whose centroids lie
/// at least half a voxel outside the region, which it never claims.
constexpr int kShellPlanes = 3;

/// One region of extractByRegionImpl(): a range of leaf layers along the grid's longest axis
/// (a slab) times a range along its second longest (a band), each [first, last).
struct Region
{
    std::pair<int, int> slab, band;
    bool firstSlab, lastSlab, firstBand, lastBand;
    size_t kept;  ///< kept leaves inside
};

/// See the comment above LeafRole. Returns false (and does nothing) when the grid has tiles
/// larger than a leaf, a transform that is not an axis-aligned scale, or makes a single
/// region; otherwise fills @a mesh, oriented outwards.
bool extractByRegionImpl(const openvdb::FloatGrid& density, double threshold, SurfaceMesh& mesh,
                         cancellation_internal::CancelPoll& poll, size_t leavesPerRegion, int minLayers,
                         openvdb::FloatTree* release, bool trimFreedMemory)
{
    const openvdb::FloatTree& tree = density.tree();
    // volumeToMesh compares values with float(threshold) but places crossings with the
    // double threshold: both as extractSurface() does.
    const float iso = float(threshold);
    std::vector<Piece> pieces;
    if (!collectPieces(tree, iso, pieces, poll) || pieces.empty()) return false;

    // Slabs across the longest axis, balanced by kept leaves (the ones volumeToMesh works on);
    // a slab with more than leavesPerRegion of them is cut again into bands across the second
    // longest axis (the dam-break frames hold 2,000 kept leaves in one layer of their floor).
    openvdb::CoordBBox bounds;
    for (const Piece& piece : pieces) bounds.expand(piece.origin);
    const openvdb::Coord extents = bounds.extents();
    const int axis = int(extents.maxIndex());
    const int cross = extents[(axis + 1) % 3] >= extents[(axis + 2) % 3] ? (axis + 1) % 3 : (axis + 2) % 3;
    const int dim = int(FloatLeaf::DIM);
    const auto layerOf = [&](const Piece& piece, int along) {
        return (piece.origin[along] - bounds.min()[along]) / dim;
    };
    const int layerCount = (bounds.max()[axis] - bounds.min()[axis]) / dim + 1;
    const int crossCount = (bounds.max()[cross] - bounds.min()[cross]) / dim + 1;
    std::vector<int> keptPerLayer(static_cast<size_t>(layerCount), 0);
    std::vector<std::vector<uint32_t>> piecesPerLayer(static_cast<size_t>(layerCount));
    std::vector<std::vector<uint32_t>> leavesPerLayer(release ? static_cast<size_t>(layerCount) : 0);
    for (size_t n = 0; n < pieces.size(); ++n) {
        const size_t layer = size_t(layerOf(pieces[n], axis));
        if (pieces[n].leaf && pieces[n].role == LeafRole::Kept) ++keptPerLayer[layer];
        if (pieces[n].role != LeafRole::Below) piecesPerLayer[layer].push_back(uint32_t(n));
        if (release && pieces[n].leaf) leavesPerLayer[layer].push_back(uint32_t(n));
    }
    int releasedLayers = 0;  // leaf layers [0, releasedLayers) freed from *release
    size_t leavesUntrimmed = 0;
    constexpr size_t kLeavesPerTrim = 32768;  // about 64 MB of leaves
    std::vector<Region> regions;
    size_t totalKept = 0;
    size_t keptWelded = 0;  // kept leaves of the regions welded so far
    {
        const std::vector<std::pair<int, int>> slabs = slabsOf(keptPerLayer, leavesPerRegion, minLayers);
        std::vector<int> keptPerBandLayer(static_cast<size_t>(crossCount));
        for (size_t s = 0; s < slabs.size(); ++s) {
            std::fill(keptPerBandLayer.begin(), keptPerBandLayer.end(), 0);
            for (int layer = slabs[s].first; layer < slabs[s].second; ++layer) {
                for (uint32_t n : piecesPerLayer[size_t(layer)]) {
                    if (pieces[n].leaf && pieces[n].role == LeafRole::Kept) ++keptPerBandLayer[size_t(layerOf(pieces[n], cross))];
                }
            }
            const std::vector<std::pair<int, int>> bands = slabsOf(keptPerBandLayer, leavesPerRegion, minLayers);
            for (size_t b = 0; b < bands.size(); ++b) {
                size_t kept = 0;
                for (int layer = bands[b].first; layer < bands[b].second; ++layer) kept += size_t(keptPerBandLayer[size_t(layer)]);
                totalKept += kept;
                regions.push_back(Region{slabs[s], bands[b], s == 0, s + 1 == slabs.size(), b == 0,
                                         b + 1 == bands.size(), kept});
            }
        }
    }
    if (regions.size() < 2) return false;

    // Seams are compared in world space, which needs an axis-aligned scale that grows with
    // the index (a claim is "centroid at or above the seam").
    const openvdb::math::Transform& transform = density.transform();
    const openvdb::math::MapBase& map = *transform.baseMap();
    if (!(map.isType<openvdb::math::UniformScaleTranslateMap>() || map.isType<openvdb::math::UniformScaleMap>()
          || map.isType<openvdb::math::ScaleTranslateMap>() || map.isType<openvdb::math::ScaleMap>())) {
        return false;
    }
    /// The world coordinate along @a along of voxel plane @a plane.
    const auto worldOf = [&](int along, int plane) {
        openvdb::Vec3d index(0.0);
        index[along] = double(plane);
        return transform.indexToWorld(index)[along];
    };
    if (!(worldOf(axis, 1) > worldOf(axis, 0)) || !(worldOf(cross, 1) > worldOf(cross, 0))) return false;

    mesh.points.clear();
    mesh.triangles.clear();
    mesh.quads.clear();
    // Vertices near the upper faces of the regions meshed so far, by exact position, and
    // their mesh index: those of the current slab, and of the slab before it (a seam
    // vertex lies within three planes of a face, and a slab is at least a leaf thick).
    SeamTable seamThisSlab, seamSlabBefore;
    // Whether a seam vertex matched a position two vertices of a region had: welding by
    // position cannot tell them apart (see weldRegion()).
    std::atomic<bool> ambiguousSeam{false};
    std::vector<uint32_t> welded, unusedNearSeam;
    std::vector<uint32_t> remap;
    std::unique_ptr<std::atomic<uint8_t>[]> used;
    std::vector<size_t> newBefore;
    std::vector<size_t> claimedBefore;
    std::vector<size_t> poolStart;      // first quad of each polygon pool, counting all pools
    std::vector<uint8_t> claimed;       // per quad of the region: whether it claims it
    constexpr uint32_t kNew = SeamTable::kNone;  // not in a seam table: a vertex of its own

    // Mesh @a region alone: its pieces plus kShellPlanes planes of the leaf layers around
    // it, tiles added serially, leaves copied (and their shells cut) in parallel, then added
    // in order. Reads the pieces of its layers only: the regions in flight run it concurrently
    // while the welding frees the layers before them all (releaseLayersBefore()).
    const auto meshRegion = [&](const Region& region) {
        const int slabBegin = bounds.min()[axis] + region.slab.first * dim;
        const int slabEnd = bounds.min()[axis] + region.slab.second * dim;
        const int bandBegin = bounds.min()[cross] + region.band.first * dim;
        const int bandEnd = bounds.min()[cross] + region.band.second * dim;
        openvdb::FloatGrid::Ptr regionGrid = openvdb::FloatGrid::create(tree.background());
        // The grid's own transform, shared (only read): transform.copy() rebuilds a translated
        // map from its matrix with a scale off in the last bits, which moved vertices by a
        // float step from the whole grid's.
        regionGrid->setTransform(std::const_pointer_cast<openvdb::math::Transform>(density.constTransformPtr()));
        regionGrid->setGridClass(density.getGridClass());
        openvdb::FloatTree& regionTree = regionGrid->tree();
        // The voxels a region keeps: kShellPlanes planes beyond each cut face, unbounded
        // along the third axis.
        openvdb::CoordBBox keep{openvdb::Coord(std::numeric_limits<int>::min()),
                                openvdb::Coord(std::numeric_limits<int>::max())};
        keep.min()[axis] = slabBegin - kShellPlanes;
        keep.max()[axis] = slabEnd + kShellPlanes - 1;
        keep.min()[cross] = bandBegin - kShellPlanes;
        keep.max()[cross] = bandEnd + kShellPlanes - 1;
        std::vector<uint32_t> regionLeaves;   // pieces of the region that are copied
        for (int layer = std::max(region.slab.first - 1, 0);
             layer <= std::min(region.slab.second, layerCount - 1); ++layer) {
            for (uint32_t n : piecesPerLayer[size_t(layer)]) {
                const Piece& piece = pieces[n];
                const int bandLayer = layerOf(piece, cross);
                if (bandLayer < region.band.first - 1 || bandLayer > region.band.second) continue;
                if (!piece.leaf || piece.role == LeafRole::Above) {
                    const openvdb::CoordBBox box = openvdb::CoordBBox::createCube(piece.origin, dim);
                    if (keep.isInside(box)) {
                        regionTree.addTile(1, piece.origin, piece.value, /*active=*/true);
                    } else {
                        // A tile across the shell's edge: a tile there would border the
                        // absent leaves beyond with a false surface (active voxels above
                        // r_0 next to the background), so a leaf of its value, cut.
                        auto* shell = new FloatLeaf(piece.origin, piece.value, /*active=*/true);
                        cutToBox(*shell, keep);
                        regionTree.addLeaf(shell);
                    }
                } else {
                    regionLeaves.push_back(n);
                }
            }
        }
        std::vector<FloatLeaf*> leafCopies(regionLeaves.size(), nullptr);  // in that order
        tbb::parallel_for(tbb::blocked_range<size_t>(0, regionLeaves.size(), 64),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t k = range.begin(); k < range.end(); ++k) {
                    const FloatLeaf& leaf = *pieces[regionLeaves[k]].leaf;
                    auto* copy = new FloatLeaf(leaf);
                    if (!keep.isInside(leaf.getNodeBoundingBox())) cutToBox(*copy, keep);
                    leafCopies[k] = copy;
                }
            });
        for (FloatLeaf* copy : leafCopies) regionTree.addLeaf(copy);
        auto mesher = std::make_unique<openvdb::tools::VolumeToMesh>(threshold, 0.0);
        (*mesher)(*regionGrid);
        return mesher;
    };

    // Layers [0, @a layer) are done with: each of their leaves becomes an inactive tile
    // (serially: only its parent node changes), so the grid shrinks as the mesh grows.
    const auto releaseLayersBefore = [&](int layer) {
        if (!release) return;
        for (; releasedLayers < layer; ++releasedLayers) {
            for (uint32_t n : leavesPerLayer[size_t(releasedLayers)]) {
                release->addTile(1, pieces[n].origin, tree.background(), /*active=*/false);
                pieces[n].leaf = nullptr;
                ++leavesUntrimmed;
            }
        }
#if defined(__GLIBC__)
        // Freed leaves (2 KB each) stay in malloc's free lists, which the mesh's large
        // arrays cannot use; hand their pages back to the system in batches. Each trim
        // walks the heap, and its page releases stall the threads meshing meanwhile (TLB
        // shootdowns), worst when the machine is busy. On the 64x benchmark input, two
        // threads, peak RSS / extract stage against trimming every 4096 leaves (8 paired
        // runs each): never 371 MB; every 32768 leaves 322 MB, -0.07 to -0.17 s; 16384
        // 302 MB, -0.01 to -0.06 s; 8192 and 4096 292 MB.
        if (trimFreedMemory && leavesUntrimmed >= kLeavesPerTrim) {
            malloc_trim(0);
            leavesUntrimmed = 0;
        }
#endif
    };

    // Append region @a r, meshed by @a mesher, to the mesh: claim its quads, weld its seam
    // vertices to those of the regions before. Regions must come in order.
    const auto weldRegion = [&](size_t r, const openvdb::tools::VolumeToMesh& mesher) {
        const Region& region = regions[r];
        if (r > 0 && region.firstBand) {
            seamSlabBefore.swap(seamThisSlab);
            seamThisSlab.clear();
        }
        // First voxel plane and one past the last, along each axis.
        const int slabBegin = bounds.min()[axis] + region.slab.first * dim;
        const int slabEnd = bounds.min()[axis] + region.slab.second * dim;
        const int bandBegin = bounds.min()[cross] + region.band.first * dim;
        const int bandEnd = bounds.min()[cross] + region.band.second * dim;

        // Claim the quads whose centroid lies in the region: both regions at a seam compute
        // the same bits for a quad there, so exactly one of them claims it.
        const size_t poolCount = mesher.polygonPoolListSize();
        const openvdb::tools::PolygonPoolList& pools = mesher.polygonPoolList();
        const openvdb::Vec3s* points = mesher.pointList().get();
        const double slabClaimBegin = worldOf(axis, slabBegin), slabClaimEnd = worldOf(axis, slabEnd);
        const double bandClaimBegin = worldOf(cross, bandBegin), bandClaimEnd = worldOf(cross, bandEnd);
        const auto centroid = [&](const openvdb::Vec4I& quad, int along) {
            return (double(points[quad[0]][along]) + double(points[quad[1]][along])
                    + double(points[quad[2]][along]) + double(points[quad[3]][along])) * 0.25;
        };
        const auto claims = [&](const openvdb::Vec4I& quad) {
            const double alongSlab = centroid(quad, axis), alongBand = centroid(quad, cross);
            return (region.firstSlab || alongSlab >= slabClaimBegin) && (region.lastSlab || alongSlab < slabClaimEnd)
                && (region.firstBand || alongBand >= bandClaimBegin) && (region.lastBand || alongBand < bandClaimEnd);
        };
        // Each quad tested once, the answer kept for the copy below (testing it again there
        // was 0.9% of the stage's instructions, by callgrind).
        poolStart.assign(poolCount + 1, 0);
        for (size_t p = 0; p < poolCount; ++p) poolStart[p + 1] = poolStart[p] + pools[p].numQuads();
        claimed.resize(poolStart[poolCount]);
        claimedBefore.assign(poolCount + 1, 0);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, poolCount),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t p = range.begin(); p < range.end(); ++p) {
                    size_t count = 0;
                    uint8_t* flags = claimed.data() + poolStart[p];
                    for (size_t q = 0; q < pools[p].numQuads(); ++q) {
                        flags[q] = claims(pools[p].quad(q));
                        count += flags[q];
                    }
                    claimedBefore[p + 1] = count;
                }
            });
        for (size_t p = 0; p < poolCount; ++p) claimedBefore[p + 1] += claimedBefore[p];
        const size_t quadBase = mesh.quads.size();
        // Room for the whole mesh, extrapolated from the welded regions' share of the kept
        // leaves (closed surfaces have about as many vertices as quads), so that the arrays
        // are seldom moved while they grow; re-extrapolated, not doubled, when they are full:
        // on the 512x benchmark input the first region's guess fell 2% short at region 135
        // of 141, and doubling gave quads and vertices 36M slots for an 18.4M mesh (no
        // measurable change in time or page faults either way).
        keptWelded += region.kept;
        const auto roomFor = [&](size_t needed) {
            return std::max(needed, size_t(1.05 * double(needed) * double(totalKept)
                                           / double(std::max<size_t>(keptWelded, 1))));
        };
        const size_t quadsNeeded = quadBase + claimedBefore[poolCount];
        if (r == 0) {
            mesh.quads.reserve(roomFor(quadsNeeded));
            mesh.points.reserve(roomFor(quadsNeeded));
        } else if (quadsNeeded > mesh.quads.capacity()) {
            mesh.quads.reserve(roomFor(quadsNeeded));
        }
        mesh.quads.resize(quadsNeeded);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, poolCount),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t p = range.begin(); p < range.end(); ++p) {
                    size_t out = quadBase + claimedBefore[p];
                    const uint8_t* flags = claimed.data() + poolStart[p];
                    for (size_t q = 0; q < pools[p].numQuads(); ++q) {
                        if (flags[q]) mesh.quads[out++] = pools[p].quad(q);  // region-local indices for now
                    }
                }
            });

        // The claimed quads' vertices, welded by exact position to those of the regions before
        // (a cell's vertices are the same bits in every grid holding its corners).
        const size_t pointCount = mesher.pointListSize();
        used.reset(new std::atomic<uint8_t>[pointCount]());
        tbb::parallel_for(tbb::blocked_range<size_t>(quadBase, mesh.quads.size()),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t q = range.begin(); q < range.end(); ++q) {
                    for (int k = 0; k < 4; ++k) used[mesh.quads[q][k]].store(1, std::memory_order_relaxed);
                }
            });
        const auto isUsed = [&](size_t n) { return used[n].load(std::memory_order_relaxed) != 0; };
        // Shared cells lie within two voxels of a seam: look up and keep only the vertices there.
        const double slabWeldBelow = worldOf(axis, slabBegin + 2), slabKeepFrom = worldOf(axis, slabEnd - 3);
        const double bandWeldBelow = worldOf(cross, bandBegin + 2), bandKeepFrom = worldOf(cross, bandEnd - 3);
        const auto nearLowerSeam = [&](const openvdb::Vec3s& p) {
            return (!region.firstSlab && double(p[axis]) < slabWeldBelow)
                || (!region.firstBand && double(p[cross]) < bandWeldBelow);
        };
        const auto nearUpperSeam = [&](const openvdb::Vec3s& p) {
            return (!region.lastSlab && double(p[axis]) >= slabKeepFrom)
                || (!region.lastBand && double(p[cross]) >= bandKeepFrom);
        };
        remap.assign(pointCount, kNew);
        if (!(region.firstSlab && region.firstBand)) {
            tbb::parallel_for(tbb::blocked_range<size_t>(0, pointCount),
                [&](const tbb::blocked_range<size_t>& range) {
                    for (size_t n = range.begin(); n < range.end(); ++n) {
                        if (!isUsed(n) || !nearLowerSeam(points[n])) continue;
                        const PositionKey key = keyOf(points[n]);
                        const uint32_t found = seamThisSlab.find(key);
                        remap[n] = found != SeamTable::kNone ? found : seamSlabBefore.find(key);
                        if (remap[n] == SeamTable::kAmbiguous) ambiguousSeam = true;
                    }
                });
            // Two vertices welded to one: both had its position. (Checked in both
            // regions: there, the position got kAmbiguous.)
            welded.clear();
            for (size_t n = 0; n < pointCount; ++n) {
                if (remap[n] != kNew) welded.push_back(remap[n]);
            }
            std::sort(welded.begin(), welded.end());
            if (std::adjacent_find(welded.begin(), welded.end()) != welded.end()) ambiguousSeam = true;
            if (ambiguousSeam) return;
        }
        // New vertices numbered in region order: a count per block, then its prefix sum.
        constexpr size_t kBlock = 16384;
        const size_t blocks = (pointCount + kBlock - 1) / kBlock;
        newBefore.assign(blocks + 1, 0);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t b = range.begin(); b < range.end(); ++b) {
                    size_t count = 0;
                    for (size_t n = b * kBlock, end = std::min(n + kBlock, pointCount); n < end; ++n) {
                        count += isUsed(n) && remap[n] == kNew;
                    }
                    newBefore[b + 1] = count;
                }
            });
        for (size_t b = 0; b < blocks; ++b) newBefore[b + 1] += newBefore[b];
        tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t b = range.begin(); b < range.end(); ++b) {
                    uint32_t next = uint32_t(mesh.points.size() + newBefore[b]);
                    for (size_t n = b * kBlock, end = std::min(n + kBlock, pointCount); n < end; ++n) {
                        if (isUsed(n) && remap[n] == kNew) remap[n] = next++;
                    }
                }
            });
        const size_t pointBase = mesh.points.size() + newBefore[blocks];
        const size_t firstNew = mesh.points.size();
        if (pointBase > mesh.points.capacity()) mesh.points.reserve(roomFor(pointBase));
        mesh.points.resize(pointBase);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, pointCount),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t n = range.begin(); n < range.end(); ++n) {
                    if (isUsed(n) && remap[n] >= firstNew) mesh.points[remap[n]] = points[n];
                }
            });
        // This region's new vertices that a later region may share. A vertex welded here
        // came from a region before, whose map still holds it for as long as it is needed.
        // Cells whose crossings fall on a shared voxel corner or face (a density exactly at
        // the threshold there, or, far from the origin, floats near a tenth of a voxel) put
        // their vertices on one point: such a position is marked, used twice or used once
        // beside an unused vertex (the next region may use the other one), and a later
        // vertex there cannot be welded. Welding by position alone joined them, and the
        // seam's quads collapsed into triangles with a repeated corner (differential hunt:
        // 2 particles 43.75 apart, -t 0 --radius 1 --voxel-size 0.5 --threshold 3
        // --region-leaves 1; the dam break 10 km out at --voxel-size 0.009). The 512x
        // benchmark input has such positions, harmlessly: none is welded.
        // This holds where three or four regions meet too: a vertex this region uses lies at
        // most one voxel plane beyond its faces, so every cell with a vertex at its position
        // has its corners in the shell, and the one input it takes from beyond (its outer
        // face's ambiguity, resolved from the cell across) regroups only crossings on that
        // face, off the position. So the region sees every vertex there that a later region
        // may use, and marks the position if there is a second (differential hunt, random
        // grids and particles with densities at the threshold, 1 to 3 leaves per region: of
        // 5 million vertices emitted where the whole grid's mesh has two or more, every
        // region saw as many at the position as that mesh has; translated out to where a
        // float step is a voxel, none fewer either).
        if (!(region.lastSlab && region.lastBand)) {
            unusedNearSeam.clear();
            for (size_t n = 0; n < pointCount; ++n) {
                if (!nearUpperSeam(points[n])) continue;
                if (!isUsed(n)) {
                    unusedNearSeam.push_back(uint32_t(n));
                } else if (remap[n] >= firstNew && !seamThisSlab.insert(keyOf(points[n]), remap[n])) {
                    seamThisSlab.markAmbiguous(keyOf(points[n]));
                }
            }
            for (const uint32_t n : unusedNearSeam) {  // beside a vertex of this region's
                const PositionKey key = keyOf(points[n]);
                const uint32_t found = seamThisSlab.find(key);
                if (found != SeamTable::kNone && found >= firstNew) seamThisSlab.markAmbiguous(key);
            }
        }
        // Mesh indices, each polygon reversed (see orientOutwards()).
        tbb::parallel_for(tbb::blocked_range<size_t>(quadBase, mesh.quads.size()),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t q = range.begin(); q < range.end(); ++q) {
                    const openvdb::Vec4I quad = mesh.quads[q];
                    mesh.quads[q] = openvdb::Vec4I(remap[quad[3]], remap[quad[2]], remap[quad[1]], remap[quad[0]]);
                }
            });
    };

    // A pipeline: regions are meshed concurrently, and each is welded, in region order (so
    // the mesh is the same whatever the thread count), while the next ones are meshed.
    // Welding is mostly short loops over one region, so a thread welding alone left the
    // other idle: on the 64x benchmark input, at two threads, 0.10 s of the stage's 0.8 s.
    // At most one region per thread, plus the one being welded, is in flight, which bounds
    // both the memory held by meshed regions and the time between two cancellation checks.
    const size_t threads = size_t(std::max(1, tbb::this_task_arena::max_concurrency()));
    std::vector<std::unique_ptr<openvdb::tools::VolumeToMesh>> meshers(regions.size());
    size_t nextRegion = 0;
    tbb::parallel_pipeline(threads + 1,
        tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order,
            [&](tbb::flow_control& control) -> size_t {
                if (nextRegion == regions.size() || poll.stopped() || ambiguousSeam) {
                    control.stop();
                    return 0;
                }
                return nextRegion++;
            })
        & tbb::make_filter<size_t, size_t>(tbb::filter_mode::parallel,
            [&](size_t r) {
                // Isolated: an exception in another region or a weld (std::bad_alloc) cancels
                // the pipeline, and volumeToMesh must not see its loops cancelled.
                if (!poll.stopped() && !ambiguousSeam) {
                    cancellation_internal::runIsolatedFromCancellation([&] { meshers[r] = meshRegion(regions[r]); });
                }
                return r;
            })
        & tbb::make_filter<size_t, void>(tbb::filter_mode::serial_in_order,
            [&](size_t r) {
                if (!meshers[r] || ambiguousSeam) return;  // stopped, or meshed whole below
                // Isolated: a thread waiting on the weld's loops must not take up the
                // meshing of another region, which would hold every later weld back.
                tbb::this_task_arena::isolate([&] { weldRegion(r, *meshers[r]); });
                meshers[r].reset();
                // Regions come in slab order along the axis and read one leaf layer before
                // their own slab, so the regions after this one need none before that.
                if (r + 1 < regions.size() && !ambiguousSeam) releaseLayersBefore(regions[r + 1].slab.first - 1);
            }));
    poll.throwIfStopped();
    if (ambiguousSeam) {
        // The caller meshes the whole grid, unless leaves were freed: then it must be made again.
        if (releasedLayers > 0) throw surface_stages_internal::AmbiguousSeamError();
        return false;
    }
    return true;
}

} // namespace

size_t tileDeepInterior(openvdb::FloatGrid& density, double threshold)
{
    requireDensityClass(density, "tileDeepInterior");
    checkExtractParameters(threshold, 0.0, double(density.background()));
    using LeafT = openvdb::FloatTree::LeafNodeType;
    openvdb::FloatTree& tree = density.tree();
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(tree);
    // Smallest value of each leaf, over all 512 voxels (inactive ones hold the background 0,
    // so a leaf with any inactive voxel never counts as inside).
    std::vector<float> leafMin(leaves.leafCount());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.leafCount()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t n = range.begin(); n < range.end(); ++n) {
                const float* values = leaves.leaf(n).buffer().data();
                leafMin[n] = *std::min_element(values, values + LeafT::SIZE);
            }
        });
    const float iso = float(threshold);
    // Look up neighbours through a map from origin to leaf number.
    std::vector<std::pair<openvdb::Coord, size_t>> byOrigin(leaves.leafCount());
    for (size_t n = 0; n < leaves.leafCount(); ++n) byOrigin[n] = {leaves.leaf(n).origin(), n};
    std::sort(byOrigin.begin(), byOrigin.end());
    const auto insideLeaf = [&](const openvdb::Coord& origin) {
        const auto it = std::lower_bound(byOrigin.begin(), byOrigin.end(), std::make_pair(origin, size_t(0)));
        return it != byOrigin.end() && it->first == origin && leafMin[it->second] > iso;
    };
    std::vector<char> deep(leaves.leafCount(), 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.leafCount()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t n = range.begin(); n < range.end(); ++n) {
                if (!(leafMin[n] > iso)) continue;
                const openvdb::Coord origin = leaves.leaf(n).origin();
                bool all = true;
                for (int dx = -1; dx <= 1 && all; ++dx)
                    for (int dy = -1; dy <= 1 && all; ++dy)
                        for (int dz = -1; dz <= 1 && all; ++dz)
                            all = insideLeaf(origin.offsetBy(dx * int(LeafT::DIM), dy * int(LeafT::DIM),
                                                             dz * int(LeafT::DIM)));
                deep[n] = all;
            }
        });
    std::vector<std::pair<openvdb::Coord, float>> tiles;
    for (size_t n = 0; n < leaves.leafCount(); ++n) {
        if (deep[n]) tiles.emplace_back(leaves.leaf(n).origin(), leafMin[n]);
    }
    for (const auto& [origin, value] : tiles) tree.addTile(1, origin, value, /*active=*/true);
    return tiles.size();
}

SurfaceMesh extractSurface(const openvdb::FloatGrid& density, double threshold, double adaptivity)
{
    requireDensityClass(density, "extractSurface");
    SurfaceMesh mesh;
    extractInto(density, threshold, adaptivity, mesh);
    return mesh;
}

SurfaceMesh extractSurface(const openvdb::DoubleGrid& density, double threshold, double adaptivity)
{
    requireDensityClass(density, "extractSurface");
    SurfaceMesh mesh;
    extractInto(density, threshold, adaptivity, mesh);
    return mesh;
}

namespace surface_stages_internal {

void extractSurfaceInto(const openvdb::FloatGrid& density, double threshold, double adaptivity,
                        size_t leavesPerRegion, SurfaceMesh& mesh,
                        openvdb::util::NullInterrupter* interrupter, openvdb::FloatTree* release,
                        bool trimFreedMemory)
{
    if (adaptivity == 0.0 && leavesPerRegion > 0) {
        extractByRegion(density, threshold, mesh, interrupter, leavesPerRegion, kMinLayersPerRegion, release,
                        trimFreedMemory);
    } else {
        extractInto(density, threshold, adaptivity, mesh);
    }
}

void extractByRegion(const openvdb::FloatGrid& density, double threshold, SurfaceMesh& mesh,
                     openvdb::util::NullInterrupter* interrupter, size_t leavesPerRegion,
                     int minLayersPerRegion, openvdb::FloatTree* release, bool trimFreedMemory)
{
    checkExtractParameters(threshold, 0.0, double(density.background()));
    cancellation_internal::CancelPoll poll(interrupter, "extract surface");
    poll.throwIfStopped();
    if (!extractByRegionImpl(density, threshold, mesh, poll, std::max<size_t>(leavesPerRegion, 1),
                             std::max(minLayersPerRegion, 1), release, trimFreedMemory)) {
        extractInto(density, threshold, 0.0, mesh);
        return;
    }
    mesh.normals.clear();
    mesh.attributes.clear();
}

} // namespace surface_stages_internal

} // namespace nonbloppy
