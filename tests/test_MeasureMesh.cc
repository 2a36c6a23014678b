// SPDX-License-Identifier: Apache-2.0
// Tests for measureMesh(): closed and open boxes, flipped faces, non-manifold edges, area
// and signed volume.

#include <nonbloppy/Error.h>
#include <nonbloppy/MeasureMesh.h>

#include <gtest/gtest.h>

#include <limits>

#include <algorithm>

namespace {

using nonbloppy::MeshMeasures;
using nonbloppy::SurfaceMesh;
using nonbloppy::measureMesh;
using nonbloppy::AreaAndVolume;
using nonbloppy::measureAreaAndVolume;

/// The cube [0,1]³ (scaled by @a size and moved by @a offset) as six quads,
/// counter-clockwise seen from outside.
SurfaceMesh
cube(float size = 1.0f, const openvdb::Vec3s& offset = openvdb::Vec3s(0.0f))
{
    SurfaceMesh mesh;
    for (int i = 0; i < 8; ++i) {
        mesh.points.push_back(offset +
            size * openvdb::Vec3s(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1)));
    }
    mesh.quads = {
        {0, 2, 3, 1}, {4, 5, 7, 6},  // z = 0, z = 1
        {0, 1, 5, 4}, {2, 6, 7, 3},  // y = 0, y = 1
        {0, 4, 6, 2}, {1, 3, 7, 5},  // x = 0, x = 1
    };
    return mesh;
}

SurfaceMesh
reversed(SurfaceMesh mesh)
{
    for (openvdb::Vec4I& q : mesh.quads) std::swap(q[1], q[3]);
    for (openvdb::Vec3I& t : mesh.triangles) std::swap(t[1], t[2]);
    return mesh;
}

SurfaceMesh
triangulated(SurfaceMesh mesh)
{
    for (const openvdb::Vec4I& q : mesh.quads) {
        mesh.triangles.emplace_back(q[0], q[1], q[2]);
        mesh.triangles.emplace_back(q[0], q[2], q[3]);
    }
    mesh.quads.clear();
    return mesh;
}

TEST(MeasureMesh, UnitCubeOfQuadsIsClosedManifoldWithAreaSixAndVolumeOne)
{
    const MeshMeasures m = measureMesh(cube());
    EXPECT_EQ(m.vertices, 8u);
    EXPECT_EQ(m.polygons, 6u);
    EXPECT_EQ(m.unusedVertices, 0u);
    EXPECT_EQ(m.nonFiniteVertices, 0u);
    EXPECT_EQ(m.zeroAreaPolygons, 0u);
    EXPECT_EQ(m.boundaryEdges, 0u);
    EXPECT_EQ(m.nonManifoldEdges, 0u);
    EXPECT_EQ(m.inconsistentEdges, 0u);
    EXPECT_TRUE(m.closed);
    EXPECT_TRUE(m.manifold);
    EXPECT_DOUBLE_EQ(m.area, 6.0);
    EXPECT_DOUBLE_EQ(m.volume, 1.0);
}

TEST(MeasureMesh, ReversedFacesGiveNegativeVolume)
{
    const MeshMeasures m = measureMesh(reversed(cube()));
    EXPECT_TRUE(m.closed);
    EXPECT_TRUE(m.manifold);  // consistently inward is still consistent
    EXPECT_DOUBLE_EQ(m.area, 6.0);
    EXPECT_DOUBLE_EQ(m.volume, -1.0);
}

TEST(MeasureMesh, TriangulatedScaledAndMovedCube)
{
    const MeshMeasures m = measureMesh(triangulated(cube(2.0f, openvdb::Vec3s(10, -5, 3))));
    EXPECT_EQ(m.polygons, 12u);
    EXPECT_TRUE(m.closed);
    EXPECT_TRUE(m.manifold);
    EXPECT_NEAR(m.area, 24.0, 1e-9);
    EXPECT_NEAR(m.volume, 8.0, 1e-9);  // independent of where the closed box is
}

TEST(MeasureMesh, TetrahedronVolumeIsOneSixth)
{
    SurfaceMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    const MeshMeasures m = measureMesh(mesh);
    EXPECT_TRUE(m.manifold);
    EXPECT_NEAR(m.volume, 1.0 / 6.0, 1e-12);
    EXPECT_NEAR(m.area, 1.5 + std::sqrt(3.0) / 2.0, 1e-9);
}

TEST(MeasureMesh, OpenBoxHasFourBoundaryEdges)
{
    SurfaceMesh box = cube();
    box.quads.erase(box.quads.begin() + 1);  // remove the top, z = 1
    const MeshMeasures m = measureMesh(box);
    EXPECT_EQ(m.polygons, 5u);
    EXPECT_EQ(m.boundaryEdges, 4u);
    EXPECT_EQ(m.nonManifoldEdges, 0u);
    EXPECT_EQ(m.inconsistentEdges, 0u);
    EXPECT_FALSE(m.closed);
    EXPECT_FALSE(m.manifold);  // manifold means every edge has exactly two polygons
    EXPECT_DOUBLE_EQ(m.area, 5.0);
    EXPECT_EQ(m.unusedVertices, 0u);
}

TEST(MeasureMesh, OneFlippedFaceMakesFourInconsistentEdges)
{
    SurfaceMesh mesh = cube();
    std::swap(mesh.quads[3][1], mesh.quads[3][3]);
    const MeshMeasures m = measureMesh(mesh);
    EXPECT_EQ(m.inconsistentEdges, 4u);
    EXPECT_EQ(m.boundaryEdges, 0u);
    EXPECT_TRUE(m.closed);
    EXPECT_FALSE(m.manifold);
    EXPECT_DOUBLE_EQ(m.area, 6.0);
}

TEST(MeasureMesh, ThreeTrianglesOnOneEdgeAreNonManifold)
{
    SurfaceMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {7, 7, 7}};
    mesh.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
    const MeshMeasures m = measureMesh(mesh);
    EXPECT_EQ(m.nonManifoldEdges, 1u);
    EXPECT_EQ(m.boundaryEdges, 6u);
    EXPECT_EQ(m.unusedVertices, 1u);
    EXPECT_FALSE(m.closed);
    EXPECT_FALSE(m.manifold);
    EXPECT_DOUBLE_EQ(m.area, 1.5);
}

TEST(MeasureMesh, TwoCubesSharingAnEdgeAreClosedButNotManifold)
{
    // Cube B sits diagonally next to cube A and shares A's edge from (1,1,0) to (1,1,1).
    SurfaceMesh mesh = cube();
    const SurfaceMesh other = cube(1.0f, openvdb::Vec3s(1, 1, 0));
    // Reuse A's vertices 3 = (1,1,0) and 7 = (1,1,1) for B's vertices 0 and 4.
    std::vector<uint32_t> remap(8);
    for (uint32_t i = 0; i < 8; ++i) {
        if (i == 0) remap[i] = 3;
        else if (i == 4) remap[i] = 7;
        else {
            remap[i] = uint32_t(mesh.points.size());
            mesh.points.push_back(other.points[i]);
        }
    }
    for (const openvdb::Vec4I& q : other.quads) {
        mesh.quads.emplace_back(remap[q[0]], remap[q[1]], remap[q[2]], remap[q[3]]);
    }
    const MeshMeasures m = measureMesh(mesh);
    EXPECT_EQ(m.nonManifoldEdges, 1u);
    EXPECT_EQ(m.boundaryEdges, 0u);
    EXPECT_TRUE(m.closed);
    EXPECT_FALSE(m.manifold);
    EXPECT_DOUBLE_EQ(m.volume, 2.0);
    EXPECT_DOUBLE_EQ(m.area, 12.0);
}

TEST(MeasureMesh, LargeGridCountsEveryEdgeOnce)
{
    // A flat n×n grid of quads has 4n boundary edges; with 300 cells a side, 360,000 edge
    // uses, filed by many threads at once. Every 7th quad of row 100 is flipped: four
    // inconsistent edges each, shared with unflipped neighbours.
    constexpr uint32_t n = 300;
    SurfaceMesh mesh;
    for (uint32_t j = 0; j <= n; ++j)
        for (uint32_t i = 0; i <= n; ++i) mesh.points.emplace_back(float(i), float(j), 0.0f);
    const auto at = [&](uint32_t i, uint32_t j) { return j * (n + 1) + i; };
    for (uint32_t j = 0; j < n; ++j) {
        for (uint32_t i = 0; i < n; ++i) {
            openvdb::Vec4I quad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            if (j == 100 && i % 7 == 3) std::swap(quad[1], quad[3]);
            mesh.quads.push_back(quad);
        }
    }
    size_t flipped = 0;
    for (uint32_t i = 0; i < n; ++i) flipped += i % 7 == 3;
    // A third polygon on each of row 200's bottom edges: a triangle (i, i+1, apex) with
    // apexes off the plane, one new vertex each.
    for (uint32_t i = 0; i < n; ++i) {
        mesh.points.emplace_back(float(i) + 0.5f, 200.0f, 1.0f);
        mesh.triangles.emplace_back(at(i, 200), at(i + 1, 200), uint32_t(mesh.points.size() - 1));
    }
    const MeshMeasures m = measureMesh(mesh);
    EXPECT_EQ(m.boundaryEdges, 4 * n + 2 * n);  // the grid's rim, and the triangles' other two sides
    EXPECT_EQ(m.inconsistentEdges, 4 * flipped);
    EXPECT_EQ(m.nonManifoldEdges, n);
    EXPECT_EQ(m.unusedVertices, 0u);
    EXPECT_FALSE(m.closed);
    EXPECT_FALSE(m.manifold);
}

TEST(MeasureMesh, APolygonCollapsedToOnePointStillUsesItsVertex)
{
    // All its edges collapse, so none of them files the vertex: it is used all the same.
    SurfaceMesh mesh = cube();
    mesh.points.push_back(openvdb::Vec3s(5.0f, 5.0f, 5.0f));  // 8
    mesh.points.push_back(openvdb::Vec3s(6.0f, 5.0f, 5.0f));  // 9, in no polygon
    mesh.triangles = {{8, 8, 8}};
    const MeshMeasures m = measureMesh(mesh);
    EXPECT_EQ(m.unusedVertices, 1u);
    EXPECT_EQ(m.zeroAreaPolygons, 1u);
    EXPECT_EQ(m.boundaryEdges, 0u);
    EXPECT_TRUE(m.manifold);
}

TEST(MeasureMesh, CountsZeroAreaPolygonsAndNonFiniteVertices)
{
    // Edges alone called a triangle with a corner repeated, or a droplet that -c 1 shrank to
    // a point, closed and manifold: the count says what they are.
    SurfaceMesh mesh = cube();
    mesh.points.push_back(mesh.points[0]);  // 8: on top of corner 0
    mesh.triangles = {{0, 0, 1},           // a corner repeated
                      {0, 8, 0}};          // and a point, twice
    mesh.quads.push_back({0, 8, 0, 8});     // a quad of one point
    MeshMeasures m = measureMesh(mesh);
    EXPECT_EQ(m.zeroAreaPolygons, 3u);
    EXPECT_EQ(m.nonFiniteVertices, 0u);
    EXPECT_DOUBLE_EQ(m.area, 6.0);
    mesh.points[8] = openvdb::Vec3s(0.0f, std::numeric_limits<float>::quiet_NaN(), 0.0f);
    mesh.points.push_back(openvdb::Vec3s(std::numeric_limits<float>::infinity(), 0.0f, 0.0f));
    mesh.points.push_back(openvdb::Vec3s(3e38f, 3e38f, 0.0f));  // finite, though their sum is not
    m = measureMesh(mesh);
    EXPECT_EQ(m.nonFiniteVertices, 2u);
    EXPECT_EQ(m.zeroAreaPolygons, 1u) << "a NaN area is not zero";
}

TEST(MeasureMesh, EmptyMeshIsNeitherClosedNorManifold)
{
    const MeshMeasures m = measureMesh(SurfaceMesh());
    EXPECT_EQ(m.polygons, 0u);
    EXPECT_FALSE(m.closed);
    EXPECT_FALSE(m.manifold);
    EXPECT_EQ(m.area, 0.0);
}

TEST(MeasureMesh, OutOfRangeIndexIsAParameterError)
{
    SurfaceMesh mesh = cube();
    mesh.triangles.emplace_back(0, 1, 99);
    try {
        measureMesh(mesh);
        FAIL() << "expected ParameterError";
    } catch (const nonbloppy::ParameterError& e) {
        EXPECT_STREQ(e.what(), "polygon 0 references vertex 99 but the mesh has 8 vertices");
    }
}

TEST(MeasureAreaAndVolume, SumsTrianglesAndQuadsAsMeasureMeshReportsThem)
{
    // A moved cube of quads plus a tetrahedron of triangles in one mesh: the analytic area and
    // volume, and the very doubles measureMesh() reports.
    SurfaceMesh mesh = cube(1.5f, openvdb::Vec3s(0.3f, -2.1f, 7.7f));
    const uint32_t base = uint32_t(mesh.points.size());
    for (const openvdb::Vec3s& p : {openvdb::Vec3s(3, 0, 0), openvdb::Vec3s(4, 0.1f, 0),
                                    openvdb::Vec3s(3, 1.3f, 0), openvdb::Vec3s(3.2f, 0, 0.9f)}) {
        mesh.points.push_back(p);
    }
    for (const openvdb::Vec3I& t : {openvdb::Vec3I(0, 2, 1), openvdb::Vec3I(0, 1, 3),
                                    openvdb::Vec3I(0, 3, 2), openvdb::Vec3I(1, 2, 3)}) {
        mesh.triangles.push_back(t + openvdb::Vec3I(base));
    }
    const MeshMeasures full = measureMesh(mesh);
    const AreaAndVolume fast = measureAreaAndVolume(mesh);
    EXPECT_EQ(fast.area, full.area);
    EXPECT_EQ(fast.volume, full.volume);
    EXPECT_NEAR(fast.volume, 1.5 * 1.5 * 1.5 + 1.0 * 1.3 * 0.9 / 6.0, 1e-5);
    EXPECT_NEAR(fast.area, 16.081966, 1e-5);  // 6 · 1.5² plus the tetrahedron's four faces
}

TEST(MeasureAreaAndVolume, OutOfRangeIndexIsAParameterError)
{
    SurfaceMesh mesh = cube();
    mesh.quads.emplace_back(0, 1, 2, 8);
    try {
        measureAreaAndVolume(mesh);
        FAIL() << "expected ParameterError";
    } catch (const nonbloppy::ParameterError& e) {
        EXPECT_STREQ(e.what(), "polygon 6 references vertex 8 but the mesh has 8 vertices");
    }
}

} // namespace
