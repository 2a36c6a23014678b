// SPDX-License-Identifier: Apache-2.0
/// @file ExtractSurface.cc
/// @brief Stage "extract surface". The only translation unit that includes
///        tools/VolumeToMesh.h (heavy to compile).
///
/// Large grids are meshed region by region (extractByRegion below): slabs of leaves, each
/// handed to volumeToMesh with a thin shell, then stitched exactly. That bounds the time
/// between two cancellation checks (volumeToMesh itself cannot be stopped) and lets every
/// region skip the leaves that no surface crossing touches.

#include <nonbloppy/Error.h>
#include <nonbloppy/ExtractSurface.h>

#include "Cancellation.h"
#include "SurfaceStages.h"

#include <openvdb/tools/VolumeToMesh.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <unordered_map>
#include <utility>
#include <sstream>

namespace nonbloppy {

namespace {

using FloatLeaf = openvdb::FloatTree::LeafNodeType;

/// @throw ParameterError unless @a threshold is finite and @a adaptivity lies in [0,1].
void checkExtractParameters(double threshold, double adaptivity)
{
    if (!std::isfinite(threshold)) {
        std::ostringstream msg;
        msg << "--threshold must be finite, got " << threshold;
        throw ParameterError(msg.str());
    }
    if (!(adaptivity >= 0.0 && adaptivity <= 1.0)) {
        std::ostringstream msg;
        msg << "--adaptivity must lie in [0,1], got " << adaptivity;
        throw ParameterError(msg.str());
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
    checkExtractParameters(threshold, adaptivity);
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
// bit-identical vertices for it. Hence a slab of leaf layers can be meshed alone from a copy
// of its leaves plus kShellPlanes voxel planes either side: each slab keeps the quads whose
// centroid lies in it (both slabs at a seam compute the same bits for a quad near it, so
// exactly one keeps it), and the vertices those quads share across a seam are welded by
// exact position. volumeToMesh's own surface mask would do the clipping too, but measured
// 20-30% slower: it rescans every crossing of the slab.

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
    // Counts rather than min/max: a branch-free loop the compiler vectorises.
    openvdb::Index below = 0;
    float low = values[0];
    for (openvdb::Index i = 0; i < FloatLeaf::SIZE; ++i) {
        below += values[i] < iso;
        low = std::min(low, values[i]);
    }
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
struct PositionKeyHash
{
    size_t operator()(const PositionKey& key) const
    {
        uint64_t h = 0x9E3779B97F4A7C15ull;
        for (uint32_t b : key.bits) h = (h ^ b) * 0x100000001B3ull;
        return size_t(h ^ (h >> 29));
    }
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

/// The slabs, as ranges [first, last) of leaf layers along @a axis, that each hold about
/// @a leavesPerRegion kept leaves and at least @a minLayers layers (a last small remainder
/// joins the slab before it).
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

/// Planes of voxels a slab's shell keeps beyond each face of the slab. A quad claimed by a
/// slab has its centroid in the slab, so its cells lie at most two voxels below the slab or
/// one above it, and their corners at most two planes out either side; volumeToMesh also
/// resolves a cell's ambiguous face from the signs of the cell across it, one plane further
/// (correctCellSigns in tools/VolumeToMesh.h), hence three. The voxels beyond are dropped;
/// the false crossings the cut makes give quads whose centroids lie at least half a voxel
/// outside the slab, which it never claims.
constexpr int kShellPlanes = 3;

/// See the comment above LeafRole. Returns false (and does nothing) when the grid has tiles
/// larger than a leaf or makes a single slab; otherwise fills @a mesh, oriented outwards.
bool extractByRegionImpl(const openvdb::FloatGrid& density, double threshold, SurfaceMesh& mesh,
                         cancellation_internal::CancelPoll& poll, size_t leavesPerRegion, int minLayers)
{
    const openvdb::FloatTree& tree = density.tree();
    // volumeToMesh compares values with float(threshold) but places crossings with the
    // double threshold: both as extractSurface() does.
    const float iso = float(threshold);
    std::vector<Piece> pieces;
    if (!collectPieces(tree, iso, pieces, poll) || pieces.empty()) return false;

    // Slabs across the longest axis, balanced by kept leaves (the ones volumeToMesh works on).
    openvdb::CoordBBox bounds;
    for (const Piece& piece : pieces) bounds.expand(piece.origin);
    const int axis = int(bounds.extents().maxIndex());
    const int dim = int(FloatLeaf::DIM);
    const int layerCount = (bounds.max()[axis] - bounds.min()[axis]) / dim + 1;
    std::vector<int> keptPerLayer(static_cast<size_t>(layerCount), 0);
    std::vector<std::vector<uint32_t>> piecesPerLayer(static_cast<size_t>(layerCount));
    for (size_t n = 0; n < pieces.size(); ++n) {
        const size_t layer = size_t((pieces[n].origin[axis] - bounds.min()[axis]) / dim);
        if (pieces[n].leaf && pieces[n].role == LeafRole::Kept) ++keptPerLayer[layer];
        if (pieces[n].role != LeafRole::Below) piecesPerLayer[layer].push_back(uint32_t(n));
    }
    const std::vector<std::pair<int, int>> slabs = slabsOf(keptPerLayer, leavesPerRegion, minLayers);
    if (slabs.size() < 2) return false;

    // Seams are compared in world space, which needs a transform without rotation.
    const openvdb::math::Transform& transform = density.transform();
    const openvdb::math::MapBase& map = *transform.baseMap();
    if (!(map.isType<openvdb::math::UniformScaleTranslateMap>() || map.isType<openvdb::math::UniformScaleMap>()
          || map.isType<openvdb::math::ScaleTranslateMap>() || map.isType<openvdb::math::ScaleMap>())
        || !(transform.voxelSize()[axis] > 0.0)) {
        return false;
    }
    /// The world coordinate along the axis of voxel plane @a plane.
    const auto worldOf = [&](int plane) {
        openvdb::Vec3d index(0.0);
        index[axis] = double(plane);
        return transform.indexToWorld(index)[axis];
    };

    mesh.points.clear();
    mesh.triangles.clear();
    mesh.quads.clear();
    // Vertices near the seam with the next slab, by exact position, and their mesh index.
    std::unordered_map<PositionKey, uint32_t, PositionKeyHash> seam;
    std::vector<uint32_t> remap;
    std::unique_ptr<std::atomic<uint8_t>[]> used;
    std::vector<size_t> newBefore;
    size_t totalKept = 0;
    for (int count : keptPerLayer) totalKept += size_t(count);
    std::vector<size_t> claimedBefore;
    constexpr uint32_t kNew = std::numeric_limits<uint32_t>::max();
    for (size_t s = 0; s < slabs.size(); ++s) {
        poll.throwIfStopped();
        const bool first = s == 0, last = s + 1 == slabs.size();
        const int slabBegin = bounds.min()[axis] + slabs[s].first * dim;   // first voxel plane
        const int slabEnd = bounds.min()[axis] + slabs[s].second * dim;    // one past the last

        // The slab's pieces plus kShellPlanes planes of the leaf layer either side.
        openvdb::FloatGrid::Ptr region = openvdb::FloatGrid::create(tree.background());
        region->setTransform(transform.copy());
        region->setGridClass(density.getGridClass());
        openvdb::FloatTree& regionTree = region->tree();
        for (int layer = std::max(slabs[s].first - 1, 0);
             layer <= std::min(slabs[s].second, layerCount - 1); ++layer) {
            const bool shell = layer < slabs[s].first || layer >= slabs[s].second;
            for (uint32_t n : piecesPerLayer[size_t(layer)]) {
                const Piece& piece = pieces[n];
                if (!piece.leaf || piece.role == LeafRole::Above) {
                    regionTree.addTile(1, piece.origin, piece.value, /*active=*/true);
                    continue;
                }
                auto* copy = new FloatLeaf(*piece.leaf);
                if (shell) {
                    for (openvdb::Index i = 0; i < FloatLeaf::SIZE; ++i) {
                        const int plane = copy->offsetToGlobalCoord(i)[axis];
                        if (plane < slabBegin - kShellPlanes || plane >= slabEnd + kShellPlanes) {
                            copy->setValueOff(i, tree.background());
                        }
                    }
                }
                regionTree.addLeaf(copy);
            }
        }
        openvdb::tools::VolumeToMesh mesher(threshold, 0.0);
        mesher(*region);
        region.reset();

        // Claim the quads whose centroid lies in the slab: both slabs at a seam compute the
        // same bits for a quad there, so exactly one of them claims it.
        const size_t poolCount = mesher.polygonPoolListSize();
        const openvdb::tools::PolygonPoolList& pools = mesher.polygonPoolList();
        const openvdb::Vec3s* points = mesher.pointList().get();
        const double claimBegin = worldOf(slabBegin), claimEnd = worldOf(slabEnd);
        const auto claims = [&](const openvdb::Vec4I& quad) {
            const double centroid = (double(points[quad[0]][axis]) + double(points[quad[1]][axis])
                                     + double(points[quad[2]][axis]) + double(points[quad[3]][axis])) * 0.25;
            return (first || centroid >= claimBegin) && (last || centroid < claimEnd);
        };
        claimedBefore.assign(poolCount + 1, 0);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, poolCount),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t p = range.begin(); p < range.end(); ++p) {
                    size_t count = 0;
                    for (size_t q = 0; q < pools[p].numQuads(); ++q) count += claims(pools[p].quad(q));
                    claimedBefore[p + 1] = count;
                }
            });
        for (size_t p = 0; p < poolCount; ++p) claimedBefore[p + 1] += claimedBefore[p];
        const size_t quadBase = mesh.quads.size();
        if (first) {
            // Room for the whole mesh, extrapolated from this slab's share of the kept leaves
            // (closed surfaces have about as many vertices as quads), so that the arrays are
            // seldom moved while they grow.
            size_t keptHere = 0;
            for (int layer = slabs[s].first; layer < slabs[s].second; ++layer) keptHere += size_t(keptPerLayer[size_t(layer)]);
            const double expected = 1.05 * double(claimedBefore[poolCount]) * double(totalKept) / double(std::max<size_t>(keptHere, 1));
            mesh.quads.reserve(size_t(expected));
            mesh.points.reserve(size_t(expected));
        }
        mesh.quads.resize(quadBase + claimedBefore[poolCount]);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, poolCount),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t p = range.begin(); p < range.end(); ++p) {
                    size_t out = quadBase + claimedBefore[p];
                    for (size_t q = 0; q < pools[p].numQuads(); ++q) {
                        const openvdb::Vec4I& quad = pools[p].quad(q);
                        if (claims(quad)) mesh.quads[out++] = quad;  // slab-local indices for now
                    }
                }
            });

        // The claimed quads' vertices, welded by exact position to the previous slab's
        // near the seam (a cell's vertices are the same bits in every grid holding its corners).
        const size_t pointCount = mesher.pointListSize();
        used.reset(new std::atomic<uint8_t>[pointCount]());
        tbb::parallel_for(tbb::blocked_range<size_t>(quadBase, mesh.quads.size()),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t q = range.begin(); q < range.end(); ++q) {
                    for (int k = 0; k < 4; ++k) used[mesh.quads[q][k]].store(1, std::memory_order_relaxed);
                }
            });
        const auto isUsed = [&](size_t n) { return used[n].load(std::memory_order_relaxed) != 0; };
        // Shared cells lie within two voxels of the seam: look up only the vertices there.
        const double weldBelow = worldOf(slabBegin + 2), keepFrom = worldOf(slabEnd - 3);
        remap.assign(pointCount, kNew);
        if (!first) {
            tbb::parallel_for(tbb::blocked_range<size_t>(0, pointCount),
                [&](const tbb::blocked_range<size_t>& range) {
                    for (size_t n = range.begin(); n < range.end(); ++n) {
                        if (!isUsed(n) || !(double(points[n][axis]) < weldBelow)) continue;
                        const auto found = seam.find(keyOf(points[n]));
                        if (found != seam.end()) remap[n] = found->second;
                    }
                });
        }
        // New vertices numbered in slab order: a count per block, then its prefix sum.
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
        mesh.points.resize(pointBase);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, pointCount),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t n = range.begin(); n < range.end(); ++n) {
                    if (isUsed(n) && remap[n] >= firstNew) mesh.points[remap[n]] = points[n];
                }
            });
        seam.clear();
        if (!last) {
            for (size_t n = 0; n < pointCount; ++n) {
                if (isUsed(n) && double(points[n][axis]) >= keepFrom) seam.emplace(keyOf(points[n]), remap[n]);
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
    }
    return true;
}

} // namespace

size_t tileDeepInterior(openvdb::FloatGrid& density, double threshold)
{
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
    SurfaceMesh mesh;
    extractInto(density, threshold, adaptivity, mesh);
    return mesh;
}

SurfaceMesh extractSurface(const openvdb::DoubleGrid& density, double threshold, double adaptivity)
{
    SurfaceMesh mesh;
    extractInto(density, threshold, adaptivity, mesh);
    return mesh;
}

namespace surface_stages_internal {

void extractSurfaceInto(const openvdb::FloatGrid& density, double threshold, double adaptivity,
                        SurfaceMesh& mesh, openvdb::util::NullInterrupter* interrupter)
{
    if (adaptivity == 0.0) {
        extractByRegion(density, threshold, mesh, interrupter, kLeavesPerRegion);
    } else {
        extractInto(density, threshold, adaptivity, mesh);
    }
}

void extractByRegion(const openvdb::FloatGrid& density, double threshold, SurfaceMesh& mesh,
                     openvdb::util::NullInterrupter* interrupter, size_t leavesPerRegion,
                     int minLayersPerRegion)
{
    checkExtractParameters(threshold, 0.0);
    cancellation_internal::CancelPoll poll(interrupter, "extract surface");
    poll.throwIfStopped();
    if (!extractByRegionImpl(density, threshold, mesh, poll, std::max<size_t>(leavesPerRegion, 1),
                             std::max(minLayersPerRegion, 1))) {
        extractInto(density, threshold, 0.0, mesh);
        return;
    }
    mesh.normals.clear();
    mesh.attributes.clear();
}

} // namespace surface_stages_internal

} // namespace nonbloppy
