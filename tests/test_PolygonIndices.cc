// SPDX-License-Identifier: Apache-2.0
// Every public function that reads a mesh's polygons refuses a corner out of range with one
// message, before it reads or moves anything. repairFolds(), countFoldedTriangles(), the
// convex preserveVolume(), computeNormals() and smoothSurface() read such corners unchecked
// (a crash) until this check was added at their boundary.

#include <nonbloppy/ComputeNormals.h>
#include <nonbloppy/CorrectSurface.h>
#include <nonbloppy/Error.h>
#include <nonbloppy/MeasureMesh.h>
#include <nonbloppy/SmoothSurface.h>

#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

namespace {

using nonbloppy::SurfaceMesh;

/// The cube [0,1]³ as six counter-clockwise quads, with its vertex normals.
SurfaceMesh cubeWithNormals()
{
    SurfaceMesh mesh;
    for (int i = 0; i < 8; ++i) {
        mesh.points.emplace_back(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
    }
    mesh.quads = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    nonbloppy::computeNormals(mesh);
    return mesh;
}

struct Stage
{
    const char* name;
    std::function<void(SurfaceMesh&)> run;
};

std::vector<Stage> meshStages()
{
    using namespace nonbloppy;
    const auto unmoved = [](const SurfaceMesh& mesh) { return mesh.points; };
    return {
        {"computeNormals", [](SurfaceMesh& m) { computeNormals(m); }},
        {"countFoldedTriangles", [=](SurfaceMesh& m) { countFoldedTriangles(m, unmoved(m)); }},
        {"repairFolds", [=](SurfaceMesh& m) { repairFolds(m, unmoved(m)); }},
        {"preserveVolume (uniform)", [](SurfaceMesh& m) { preserveVolume(m, 2.0); }},
        {"preserveVolume (convex)", [](SurfaceMesh& m) {
             VolumeSettings settings;
             settings.targetVolume = 2.0;
             settings.offset = VolumeOffset::Convex;
             preserveVolume(m, settings);
         }},
        {"smoothSurface", [](SurfaceMesh& m) {
             SmoothSettings settings;
             settings.spatialWidth = 0.5;
             smoothSurface(m, settings);
         }},
        {"measureMesh", [](SurfaceMesh& m) { measureMesh(m); }},
        {"measureAreaAndVolume", [](SurfaceMesh& m) { measureAreaAndVolume(m); }},
    };
}

void expectRefused(SurfaceMesh mesh, const std::string& message)
{
    for (const Stage& stage : meshStages()) {
        SCOPED_TRACE(stage.name);
        SurfaceMesh copy = mesh;
        try {
            stage.run(copy);
            ADD_FAILURE() << "no exception";
        } catch (const nonbloppy::ParameterError& error) {
            EXPECT_EQ(std::string(error.what()), message);
        }
        EXPECT_EQ(copy.points, mesh.points);
        EXPECT_EQ(copy.normals, mesh.normals);
    }
}

TEST(PolygonIndices, EveryMeshStageRefusesAQuadCornerOutOfRange)
{
    SurfaceMesh mesh = cubeWithNormals();
    mesh.quads[4][2] = 8;  // one past the last vertex
    expectRefused(mesh, "polygon 4 references vertex 8 but the mesh has 8 vertices");
}

TEST(PolygonIndices, EveryMeshStageRefusesATriangleCornerFarOutOfRange)
{
    // Triangles are numbered before quads (as the writers number them): the bad triangle is
    // polygon 1 although the bad quad comes first in memory.
    SurfaceMesh mesh = cubeWithNormals();
    mesh.triangles = {{0, 2, 1}, {4, 100000000, 6}};
    mesh.quads[0][0] = 9;
    expectRefused(mesh, "polygon 1 references vertex 100000000 but the mesh has 8 vertices");
}

TEST(PolygonIndices, TheStagesStillWorkOnAValidMesh)
{
    // The check refuses nothing valid: each stage runs on the cube (a test of the check, not
    // of the stages, which their own tests cover).
    for (const Stage& stage : meshStages()) {
        SCOPED_TRACE(stage.name);
        SurfaceMesh mesh = cubeWithNormals();
        EXPECT_NO_THROW(stage.run(mesh));
    }
}

} // namespace
