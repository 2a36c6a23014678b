// SPDX-License-Identifier: Apache-2.0
// The only translation unit that includes tools/VolumeToMesh.h (heavy to compile).
#include <nonbloppy/Error.h>
#include <nonbloppy/ExtractSurface.h>

#include "SurfaceStages.h"

#include <openvdb/tools/VolumeToMesh.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <sstream>

namespace nonbloppy {

namespace {

/// volumeToMesh into @a mesh's vectors (it clears and resizes them, so they keep their
/// capacity), then every polygon reversed; normals and attributes cleared.
template<typename GridT>
void extractInto(const GridT& density, double threshold, double adaptivity, SurfaceMesh& mesh)
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
    openvdb::tools::volumeToMesh(density, mesh.points, mesh.triangles, mesh.quads, threshold, adaptivity);
    // The density grows inwards, the opposite of a level set, so volumeToMesh's polygons run
    // clockwise seen from outside: reverse each one.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.quads.size()),
        [&](const tbb::blocked_range<size_t>& range) {
            for (size_t n = range.begin(); n < range.end(); ++n) {
                const openvdb::Vec4I q = mesh.quads[n];
                mesh.quads[n] = openvdb::Vec4I(q[3], q[2], q[1], q[0]);
            }
        });
    for (openvdb::Vec3I& t : mesh.triangles) std::swap(t[0], t[2]);
    mesh.normals.clear();
    mesh.attributes.clear();
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
                        SurfaceMesh& mesh)
{
    extractInto(density, threshold, adaptivity, mesh);
}

} // namespace surface_stages_internal

} // namespace nonbloppy
