// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/ComputeNormals.h>

#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <random>

using nonbloppy::SurfaceMesh;
using nonbloppy::computeNormals;

namespace {

/// The normal sums written out the plain way: every polygon in order (triangles, then quads)
/// adds twice its vector area, in double, to each of its corners.
std::vector<openvdb::Vec3s> referenceNormals(const SurfaceMesh& mesh)
{
    const auto& p = mesh.points;
    std::vector<openvdb::Vec3d> sums(p.size(), openvdb::Vec3d(0.0));
    for (const openvdb::Vec3I& t : mesh.triangles) {
        const openvdb::Vec3d a(p[t[0]]), b(p[t[1]]), c(p[t[2]]);
        const openvdb::Vec3d normal = (b - a).cross(c - a);
        for (int k = 0; k < 3; ++k) sums[t[k]] += normal;
    }
    for (const openvdb::Vec4I& q : mesh.quads) {
        const openvdb::Vec3d a(p[q[0]]), b(p[q[1]]), c(p[q[2]]), d(p[q[3]]);
        const openvdb::Vec3d normal = (c - a).cross(d - b);  // a quad's: its diagonals crossed
        for (int k = 0; k < 4; ++k) sums[q[k]] += normal;
    }
    std::vector<openvdb::Vec3s> normals(p.size());
    for (size_t i = 0; i < p.size(); ++i) {
        const double length = sums[i].length();
        normals[i] = length > 0.0 ? openvdb::Vec3s(sums[i] / length) : openvdb::Vec3s(0.0f);
    }
    return normals;
}

/// A height field z = f(x, y) of @a n × @a n vertices as quads, except every fifth cell,
/// which is two triangles; vertices in a random order, so polygons and vertex numbers do
/// not follow each other (the worst case for the ranges of computeNormals()).
SurfaceMesh bumpyPatch(int n, bool shuffled)
{
    SurfaceMesh mesh;
    std::vector<uint32_t> number(size_t(n) * n);
    for (size_t i = 0; i < number.size(); ++i) number[i] = uint32_t(i);
    if (shuffled) std::shuffle(number.begin(), number.end(), std::mt19937(7));
    mesh.points.resize(number.size());
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
            const float x = 0.01f * float(i), y = 0.01f * float(j);
            mesh.points[number[size_t(i) * n + j]] =
                openvdb::Vec3s(x, y, 0.05f * std::sin(7.0f * x) * std::cos(5.0f * y) + 1e-3f * float((i * j) % 7));
        }
    }
    const auto at = [&](int i, int j) { return number[size_t(i) * n + j]; };
    for (int i = 0; i + 1 < n; ++i) {
        for (int j = 0; j + 1 < n; ++j) {
            if ((i + j) % 5 == 0) {
                mesh.triangles.emplace_back(at(i, j), at(i + 1, j), at(i + 1, j + 1));
                mesh.triangles.emplace_back(at(i, j), at(i + 1, j + 1), at(i, j + 1));
            } else {
                mesh.quads.emplace_back(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            }
        }
    }
    return mesh;
}

} // namespace

TEST(ComputeNormals, CubeCornersPointAlongTheirDiagonal)
{
    SurfaceMesh cube;
    for (int i = 0; i < 8; ++i) cube.points.emplace_back(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
    cube.quads = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    computeNormals(cube);
    ASSERT_EQ(cube.normals.size(), 8u);
    for (int i = 0; i < 8; ++i) {
        const openvdb::Vec3s outward = (cube.points[i] - openvdb::Vec3s(0.5f)).unitSafe();
        EXPECT_NEAR(cube.normals[i].dot(outward), 1.0f, 1e-6f) << "corner " << i;
    }
}

TEST(ComputeNormals, UnusedVertexGetsZeroAndFlatPatchGetsItsPlaneNormal)
{
    SurfaceMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {5, 5, 5}};
    mesh.triangles = {{0, 1, 2}};
    mesh.quads = {{0, 2, 3, 3}};  // degenerate corner repeated: still a valid area
    computeNormals(mesh);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(mesh.normals[i], openvdb::Vec3s(0, 0, 1)) << i;
    EXPECT_EQ(mesh.normals[4], openvdb::Vec3s(0.0f));
}

TEST(ComputeNormals, SameBitsAsThePlainSumForAnyThreadCount)
{
    // 600 × 600 vertices: eleven ranges of vertex numbers in order, one sum when shuffled.
    // The third case adds triangles whose corners lie 30,000 vertices apart: their block of
    // polygons touches every range, more than computeNormals() lists one by one.
    for (int variant = 0; variant < 3; ++variant) {
        const bool shuffled = variant == 1;
        SurfaceMesh patch = bumpyPatch(600, shuffled);
        if (variant == 2) {
            for (uint32_t i = 0; i + 2 * 30000 < 600 * 600; i += 30000) {
                patch.triangles.emplace_back(i, i + 30000, i + 2 * 30000);
            }
        }
        const std::vector<openvdb::Vec3s> expected = referenceNormals(patch);
        for (int threads : {1, 2, 3, 8}) {
            SurfaceMesh mesh = patch;
            tbb::task_arena(threads).execute([&] { computeNormals(mesh); });
            ASSERT_EQ(mesh.normals.size(), expected.size());
            size_t differing = 0;
            for (size_t i = 0; i < expected.size(); ++i) differing += mesh.normals[i] != expected[i];
            EXPECT_EQ(differing, 0u) << threads << " threads, variant " << variant;
        }
    }
}

TEST(ComputeNormals, ReusesTheRoomOfEarlierNormals)
{
    // A mesh meshed again (SurfaceReconstructor's, frame after frame) keeps its normals'
    // memory instead of faulting in fresh pages; the values are the new frame's.
    SurfaceMesh mesh = bumpyPatch(300, false);
    computeNormals(mesh);
    const openvdb::Vec3s* before = mesh.normals.data();
    for (openvdb::Vec3s& p : mesh.points) p[2] = -p[2];
    computeNormals(mesh);
    EXPECT_EQ(mesh.normals.data(), before);
    EXPECT_EQ(mesh.normals, referenceNormals(mesh));
}
