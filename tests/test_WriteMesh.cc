// SPDX-License-Identifier: Apache-2.0
// Tests for writeMesh(), readMesh() and the AtomicFile helper: round trips through all three
// formats, exact bytes, atomic replacement and clean failure.

#include "TestUtil.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/MeasureMesh.h>
#include <nonbloppy/ReadMesh.h>
#include <nonbloppy/ReadParticles.h>
#include <nonbloppy/WriteMesh.h>
#include <nonbloppy/WriteParticles.h>

#include "../src/AtomicFile.h"

#include <gtest/gtest.h>

#include <charconv>

#include <csignal>
#include <sys/resource.h>

#include <tbb/global_control.h>

#include <dirent.h>
#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <random>
#include <iterator>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using nonbloppy_test::dataPath;
using nonbloppy_test::messageOf;
using nonbloppy_test::readBytes;
using nonbloppy_test::writeBytes;

using nonbloppy::declaresPolygons;
using nonbloppy::FileError;
using nonbloppy::MeshWriteSettings;
using nonbloppy::SurfaceMesh;
using nonbloppy::readMesh;
using nonbloppy::writeMesh;

std::set<std::string>
listDirectory(const std::string& dir)
{
    std::set<std::string> names;
    if (DIR* d = opendir(dir.c_str())) {
        while (dirent* entry = readdir(d)) {
            const std::string name = entry->d_name;
            if (name != "." && name != "..") names.insert(name);
        }
        closedir(d);
    }
    return names;
}


/// A unit cube with corners at 0 and 1 and six outward-facing (counter-clockwise) quads.
SurfaceMesh
unitCube()
{
    SurfaceMesh mesh;
    for (int i = 0; i < 8; ++i) {
        mesh.points.emplace_back(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
    }
    mesh.quads = {
        {0, 2, 3, 1}, {4, 5, 7, 6},  // z = 0 (facing -z), z = 1 (+z)
        {0, 1, 5, 4}, {2, 6, 7, 3},  // y = 0, y = 1
        {0, 4, 6, 2}, {1, 3, 7, 5},  // x = 0, x = 1
    };
    return mesh;
}

/// A mesh with triangles and quads, non-trivial float values and unit normals.
SurfaceMesh
mixedMesh()
{
    SurfaceMesh mesh;
    mesh.points = {{0.1f, -2.5f, 3e-5f}, {1.0f / 3.0f, 2.0f, 1e7f}, {-0.0f, 0.7f, 4.25f},
                   {5.5f, 6.5f, 7.5f}, {123.456f, -0.001f, 0.0f}};
    mesh.normals = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.6f, 0.8f, 0}, {0, -0.6f, 0.8f}};
    mesh.triangles = {{0, 1, 2}, {2, 3, 4}};
    mesh.quads = {{0, 1, 3, 4}, {4, 3, 2, 1}};
    return mesh;
}

class WriteMeshTest : public nonbloppy_test::ScratchDirTest
{
};

/// The mesh @a mesh should read back as after writing with @a keepQuads.
SurfaceMesh
expectedAfterWrite(const SurfaceMesh& mesh, bool keepQuads)
{
    SurfaceMesh expected = mesh;
    if (!keepQuads) {
        expected.quads.clear();
        for (const openvdb::Vec4I& q : mesh.quads) {
            expected.triangles.emplace_back(q[0], q[1], q[2]);
            expected.triangles.emplace_back(q[0], q[2], q[3]);
        }
    }
    return expected;
}

void
expectSameMesh(const SurfaceMesh& actual, const SurfaceMesh& expected)
{
    ASSERT_EQ(actual.points.size(), expected.points.size());
    for (size_t i = 0; i < expected.points.size(); ++i) {
        EXPECT_EQ(actual.points[i], expected.points[i]) << "point " << i;
    }
    ASSERT_EQ(actual.normals.size(), expected.normals.size());
    for (size_t i = 0; i < expected.normals.size(); ++i) {
        EXPECT_EQ(actual.normals[i], expected.normals[i]) << "normal " << i;
    }
    EXPECT_EQ(actual.triangles, expected.triangles);
    EXPECT_EQ(actual.quads, expected.quads);
}

TEST_F(WriteMeshTest, RoundTripThroughEveryFormatWithQuadsKeptAndSplit)
{
    const SurfaceMesh cube = unitCube(), mixed = mixedMesh();
    SurfaceMesh withoutNormals = mixedMesh();
    withoutNormals.normals.clear();
    for (const char* ext : {".obj", ".ply", ".vtk", ".OBJ"}) {
        for (bool keepQuads : {true, false}) {
            for (const SurfaceMesh* mesh : std::vector<const SurfaceMesh*>{&cube, &mixed, &withoutNormals}) {
                SCOPED_TRACE(std::string(ext) + (keepQuads ? " keep" : " split") +
                    " points " + std::to_string(mesh->points.size()) +
                    (mesh->normals.empty() ? "" : " normals"));
                const std::string p = path(std::string("mesh") + ext);
                MeshWriteSettings settings;
                settings.keepQuads = keepQuads;
                writeMesh(*mesh, p, settings);
                expectSameMesh(readMesh(p), expectedAfterWrite(*mesh, keepQuads));
                EXPECT_EQ(listDirectory(dir()), std::set<std::string>{std::string("mesh") + ext});
                std::remove(p.c_str());
            }
        }
    }
}

TEST_F(WriteMeshTest, OutputIsDeterministicAndOfTheDocumentedLayout)
{
    const SurfaceMesh mesh = mixedMesh();
    for (const char* ext : {".obj", ".ply", ".vtk"}) {
        writeMesh(mesh, path(std::string("a") + ext));
        writeMesh(mesh, path(std::string("b") + ext));
        const std::string first = readBytes(path(std::string("a") + ext));
        writeMesh(mesh, path(std::string("a") + ext));  // overwrite
        EXPECT_EQ(first, readBytes(path(std::string("a") + ext))) << ext;
        EXPECT_EQ(first, readBytes(path(std::string("b") + ext))) << ext;
    }

    // PLY: fixed header, then 24 bytes per vertex and 13 bytes per (split) triangle.
    const std::string ply = readBytes(path("a.ply"));
    const std::string header =
        "ply\nformat binary_little_endian 1.0\ncomment written by nonbloppy\n"
        "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\n"
        "element face 6\nproperty list uchar int vertex_indices\nend_header\n";
    ASSERT_EQ(ply.substr(0, header.size()), header);
    EXPECT_EQ(ply.size(), header.size() + 5 * 24 + 6 * 13);

    // VTK: big-endian float coordinates right after the POINTS line.
    const std::string vtk = readBytes(path("a.vtk"));
    const std::string pointsLine = "DATASET POLYDATA\nPOINTS 5 float\n";
    const size_t start = vtk.find(pointsLine);
    ASSERT_NE(start, std::string::npos);
    const unsigned char* x0 =
        reinterpret_cast<const unsigned char*>(vtk.data() + start + pointsLine.size());
    const uint32_t bits = (uint32_t(x0[0]) << 24) | (uint32_t(x0[1]) << 16) |
        (uint32_t(x0[2]) << 8) | uint32_t(x0[3]);
    float x;
    std::memcpy(&x, &bits, 4);
    EXPECT_EQ(x, 0.1f);
    EXPECT_NE(vtk.find("\nPOLYGONS 6 24\n"), std::string::npos);
    EXPECT_NE(vtk.find("\nPOINT_DATA 5\nNORMALS normals float\n"), std::string::npos);
}

/// PLY as the format says, one value at a time: the reference for the batched writer.
static std::string
referencePly(const SurfaceMesh& mesh)
{
    std::string bytes = "ply\nformat binary_little_endian 1.0\ncomment written by nonbloppy\n"
        "element vertex " + std::to_string(mesh.points.size()) + "\nproperty float x\n"
        "property float y\nproperty float z\nproperty float nx\nproperty float ny\n"
        "property float nz\nelement face " + std::to_string(mesh.triangles.size() + 2 * mesh.quads.size())
        + "\nproperty list uchar int vertex_indices\nend_header\n";
    auto put = [&](auto value) {
        static_assert(sizeof(value) == 4, "4 bytes");
        unsigned char le[4];
        uint32_t bits;
        std::memcpy(&bits, &value, 4);
        for (int b = 0; b < 4; ++b) le[b] = static_cast<unsigned char>(bits >> (8 * b));
        bytes.append(reinterpret_cast<const char*>(le), 4);
    };
    for (size_t i = 0; i < mesh.points.size(); ++i) {
        for (int a = 0; a < 3; ++a) put(mesh.points[i][a]);
        for (int a = 0; a < 3; ++a) put(mesh.normals[i][a]);
    }
    auto triangle = [&](uint32_t a, uint32_t b, uint32_t c) {
        bytes.push_back(3);
        put(int32_t(a));
        put(int32_t(b));
        put(int32_t(c));
    };
    for (const openvdb::Vec3I& t : mesh.triangles) triangle(t[0], t[1], t[2]);
    for (const openvdb::Vec4I& q : mesh.quads) {
        triangle(q[0], q[1], q[2]);
        triangle(q[0], q[2], q[3]);
    }
    return bytes;
}

/// A mesh of @a vertices random points and normals in [-extent, extent]^3 (fixed @a seed) and
/// @a triangles and @a quads of random corners: the bytes of every format at every size.
SurfaceMesh
randomMesh(unsigned seed, float extent, int vertices, int triangles, int quads)
{
    SurfaceMesh mesh;
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> coordinate(-extent, extent);
    std::uniform_int_distribution<uint32_t> vertex(0, uint32_t(vertices - 1));
    for (int i = 0; i < vertices; ++i) {
        mesh.points.emplace_back(coordinate(random), coordinate(random), coordinate(random));
        mesh.normals.emplace_back(coordinate(random), coordinate(random), coordinate(random));
    }
    for (int i = 0; i < triangles; ++i) mesh.triangles.emplace_back(vertex(random), vertex(random), vertex(random));
    for (int i = 0; i < quads; ++i) {
        mesh.quads.emplace_back(vertex(random), vertex(random), vertex(random), vertex(random));
    }
    return mesh;
}

TEST_F(WriteMeshTest, BatchedParallelEncodingMatchesTheFormatAtAnyThreadCount)
{
    // Enough polygons for several 8 MB batches of split quads (26 bytes each), so that a
    // batch is encoded while the one before is written.
    const SurfaceMesh mesh = randomMesh(11, 10.0f, 100000, 30000, 1400000);
    const std::string expected = referencePly(mesh);
    ASSERT_GT(expected.size(), size_t(4) * (8 << 20));
    {
        tbb::global_control oneThread(tbb::global_control::max_allowed_parallelism, 1);
        writeMesh(mesh, path("one.ply"));
        writeMesh(mesh, path("one.vtk"));
    }
    writeMesh(mesh, path("many.ply"));
    writeMesh(mesh, path("many.vtk"));
    EXPECT_TRUE(readBytes(path("one.ply")) == expected);
    EXPECT_TRUE(readBytes(path("many.ply")) == expected);
    EXPECT_TRUE(readBytes(path("one.vtk")) == readBytes(path("many.vtk")));
    const SurfaceMesh back = readMesh(path("many.vtk"));
    ASSERT_EQ(back.points.size(), mesh.points.size());
    ASSERT_EQ(back.triangles.size(), mesh.triangles.size() + 2 * mesh.quads.size());
    EXPECT_EQ(back.points.back(), mesh.points.back());
    EXPECT_EQ(back.triangles.back(), openvdb::Vec3I(mesh.quads.back()[0], mesh.quads.back()[2], mesh.quads.back()[3]));
}

/// The OBJ text writeMesh() documents for @a mesh, one value at a time: shortest round-trip
/// numbers, faces with 1-based "i//i" corners where the mesh has normals.
std::string
referenceObj(const SurfaceMesh& mesh, bool keepQuads)
{
    std::string text = "# nonbloppy surface mesh\n";
    auto number = [&](auto value) {
        char digits[32];
        text.append(digits, size_t(std::to_chars(digits, digits + sizeof(digits), value).ptr - digits));
    };
    auto vector = [&](const char* tag, const openvdb::Vec3s& v) {
        text += tag;
        for (int a = 0; a < 3; ++a) {
            text += ' ';
            number(v[a]);
        }
        text += '\n';
    };
    for (const openvdb::Vec3s& p : mesh.points) vector("v", p);
    for (const openvdb::Vec3s& n : mesh.normals) vector("vn", n);
    auto face = [&](std::vector<uint32_t> corners) {
        text += 'f';
        for (const uint32_t c : corners) {
            text += ' ';
            number(uint64_t(c) + 1);
            if (!mesh.normals.empty()) {
                text += "//";
                number(uint64_t(c) + 1);
            }
        }
        text += '\n';
    };
    for (const openvdb::Vec3I& t : mesh.triangles) face({t[0], t[1], t[2]});
    for (const openvdb::Vec4I& q : mesh.quads) {
        if (keepQuads) {
            face({q[0], q[1], q[2], q[3]});
        } else {
            face({q[0], q[1], q[2]});
            face({q[0], q[2], q[3]});
        }
    }
    return text;
}

TEST_F(WriteMeshTest, ObjLinesFormattedInParallelMatchTheFormatAtAnyThreadCount)
{
    // Lines are formatted in pieces of 4096, in parallel, and written in order: dozens of
    // pieces of each kind of line, the last ones short.
    SurfaceMesh mesh = randomMesh(5, 1000.0f, 200001, 30000, 200000);
    const std::string expected = referenceObj(mesh, /*keepQuads=*/false);
    {
        tbb::global_control oneThread(tbb::global_control::max_allowed_parallelism, 1);
        writeMesh(mesh, path("one.obj"));
    }
    writeMesh(mesh, path("many.obj"));
    EXPECT_TRUE(readBytes(path("one.obj")) == expected);
    EXPECT_TRUE(readBytes(path("many.obj")) == expected);
    MeshWriteSettings keep;
    keep.keepQuads = true;
    mesh.normals.clear();
    writeMesh(mesh, path("quads.obj"), keep);
    EXPECT_TRUE(readBytes(path("quads.obj")) == referenceObj(mesh, /*keepQuads=*/true));
}

TEST_F(WriteMeshTest, AttributeNamesStayDistinctFromEachOtherAndFromTheFormatsColumns)
{
    // Before, names only lost their whitespace: "a b" beside "a_b" gave two properties
    // a_b, and an attribute "nx" a second nx beside the normals, which readers resolve
    // either way. Now they are written as the particle writers write them.
    SurfaceMesh mesh = mixedMesh();  // with normals
    const auto add = [&](const std::string& name, int components, float first) {
        nonbloppy::MeshAttribute a;
        a.name = name;
        a.components = components;
        for (size_t k = 0; k < mesh.points.size() * size_t(components); ++k) a.values.push_back(first + float(k));
        mesh.attributes.push_back(a);
    };
    add("a b", 1, 10.0f);
    add("a_b", 1, 20.0f);
    add("nx", 1, 30.0f);
    add("x", 3, 40.0f);      // x_x, x_y, x_z: free
    add("y", 1, 60.0f);      // the positions' y
    add("normals", 1, 70.0f);
    add("", 1, 80.0f);
    const std::vector<std::string> ply{"a_b_2", "a_b", "nx_2", "x", "y_2", "normals", "attribute"};
    const std::vector<std::string> vtk{"a_b_2", "a_b", "nx", "x", "y", "normals_2", "attribute"};
    EXPECT_EQ(nonbloppy::writtenAttributeNames(mesh, path("m.ply")), ply);
    EXPECT_EQ(nonbloppy::writtenAttributeNames(mesh, path("m.vtk")), vtk);
    EXPECT_EQ(nonbloppy::writtenAttributeNames(mesh, path("m.obj")), std::vector<std::string>(7, ""));
    EXPECT_EQ(messageOf<FileError>([&] { nonbloppy::writtenAttributeNames(mesh, path("m.stl")); }),
              "unknown mesh file extension '.stl' (" + path("m.stl") + "); expected .obj, .ply or .vtk");

    writeMesh(mesh, path("m.ply"));
    const std::string bytes = readBytes(path("m.ply"));
    EXPECT_NE(bytes.find("property float nx\nproperty float ny\nproperty float nz\nproperty float a_b_2\n"
                         "property float a_b\nproperty float nx_2\nproperty float x_x\nproperty float x_y\n"
                         "property float x_z\nproperty float y_2\nproperty float normals\n"
                         "property float attribute\nelement face"), std::string::npos);
    // Read back as particles: every name once, each with its own values.
    const nonbloppy::ParticleSet back = nonbloppy::readParticles(path("m.ply"));
    ASSERT_EQ(back.size(), mesh.points.size());
    for (size_t i = 0; i < ply.size(); ++i) {
        if (mesh.attributes[i].components != 1) continue;
        const nonbloppy::ParticleAttribute* a = back.findAttribute(ply[i]);
        ASSERT_NE(a, nullptr) << ply[i];
        for (size_t n = 0; n < back.size(); ++n) EXPECT_EQ(float(a->asDouble(n)), mesh.attributes[i].values[n]) << ply[i];
    }
    EXPECT_EQ(back.positions[1], mesh.points[1]);

    writeMesh(mesh, path("m.vtk"));
    const std::string vtkBytes = readBytes(path("m.vtk"));
    EXPECT_NE(vtkBytes.find("NORMALS normals float\n"), std::string::npos);
    EXPECT_NE(vtkBytes.find("SCALARS normals_2 float 1\n"), std::string::npos);
    EXPECT_NE(vtkBytes.find("SCALARS a_b_2 float 1\n"), std::string::npos);
    EXPECT_NE(vtkBytes.find("VECTORS x float\n"), std::string::npos);

    // Without normals, nx, ny, nz are free in PLY.
    mesh.normals.clear();
    EXPECT_EQ(nonbloppy::writtenAttributeNames(mesh, path("m.ply"))[2], "nx");
}

TEST_F(WriteMeshTest, IntegerAttributesAreWrittenExactlyInTheNarrowestTypeThatHoldsThem)
{
    // Ids carried to the vertices (MeshAttribute::integer) were float32 values, which skip
    // integers past 2^24: a 20-million-particle frame's ids came out rounded to a
    // neighbour's. They are 64-bit integers now, written as int where every value fits,
    // else PLY uint or double (PLY has no 64-bit integer) and VTK vtktypeint64.
    SurfaceMesh mesh = mixedMesh();
    const size_t n = mesh.points.size();
    const auto addIntegers = [&](const std::string& name, int components, const std::function<int64_t(size_t)>& value) {
        nonbloppy::MeshAttribute a;
        a.name = name;
        a.components = components;
        a.integer = true;
        for (size_t k = 0; k < n * size_t(components); ++k) a.integers.push_back(value(k));
        mesh.attributes.push_back(a);
    };
    const int64_t kInt32Max = std::numeric_limits<int32_t>::max();
    const int64_t kTwoTo40 = int64_t(1) << 40;
    addIntegers("id", 1, [&](size_t k) { return kInt32Max - int64_t(k); });             // int, past 2^24
    addIntegers("cell", 3, [](size_t k) { return -int64_t(k); });                         // int, VECTORS
    addIntegers("serial", 1, [&](size_t k) { return kInt32Max + 1 + int64_t(k); });       // PLY uint
    addIntegers("huge", 1, [&](size_t k) { return k == 0 ? -kTwoTo40 - 1 : int64_t(k); }); // PLY double
    addIntegers("five", 5, [](size_t k) { return int64_t(k % 7); });                       // int, a FIELD array
    nonbloppy::MeshAttribute count;  // floats: not integer
    count.name = "count";
    for (size_t k = 0; k < n; ++k) count.values.push_back(float(k) + 0.5f);
    mesh.attributes.push_back(count);

    writeMesh(mesh, path("m.ply"));
    const std::string bytes = readBytes(path("m.ply"));
    EXPECT_NE(bytes.find("property int id\nproperty int cell_x\nproperty int cell_y\nproperty int cell_z\n"
                         "property uint serial\nproperty double huge\nproperty int five_0\n"),
              std::string::npos);
    EXPECT_NE(bytes.find("property int five_4\nproperty float count\nelement face"), std::string::npos);
    writeMesh(mesh, path("m.vtk"));
    const std::string vtk = readBytes(path("m.vtk"));
    const std::string field = "FIELD FieldData 1\nfive 5 " + std::to_string(n) + " int\n";
    for (const std::string header : {"SCALARS id int 1\n", "VECTORS cell int\n", "SCALARS serial vtktypeint64 1\n",
                                     "SCALARS huge vtktypeint64 1\n", "SCALARS count float 1\n", field.c_str()}) {
        EXPECT_NE(vtk.find(header), std::string::npos) << header;
    }
    // Read back as particles: every value exact.
    using nonbloppy::ScalarType;
    for (const std::string file : {"m.ply", "m.vtk"}) {
        const bool ply = file == "m.ply";
        const nonbloppy::ParticleSet back = nonbloppy::readParticles(path(file));
        for (const nonbloppy::MeshAttribute& written : mesh.attributes) {
            const nonbloppy::ParticleAttribute* a = back.findAttribute(written.name);  // PLY five_0..five_4: one again
            ASSERT_NE(a, nullptr) << file << " " << written.name;
            EXPECT_EQ(a->components, written.components) << file << " " << written.name;
            for (size_t k = 0; k < written.size(); ++k) {
                ASSERT_EQ(a->asDouble(k / size_t(written.components), int(k % size_t(written.components))),
                          written.asDouble(k)) << file << " " << written.name << " " << k;
            }
        }
        EXPECT_EQ(back.findAttribute("id")->type, ScalarType::Int32) << file;
        EXPECT_EQ(back.findAttribute("serial")->type, ply ? ScalarType::UInt32 : ScalarType::Int64) << file;
        EXPECT_EQ(back.findAttribute("huge")->type, ply ? ScalarType::Float64 : ScalarType::Int64) << file;
        EXPECT_EQ(back.findAttribute("count")->type, ScalarType::Float32) << file;
    }
    // Every value above fits a double exactly; one past 2^53 is rounded by PLY only.
    EXPECT_TRUE(nonbloppy::roundedAttributes(mesh, path("m.ply")).empty());
    addIntegers("past", 1, [](size_t k) { return k == 1 ? -(int64_t(1) << 53) - 1 : int64_t(k); });
    EXPECT_EQ(nonbloppy::roundedAttributes(mesh, path("m.ply")), std::vector<std::string>{"past"});
    EXPECT_TRUE(nonbloppy::roundedAttributes(mesh, path("m.vtk")).empty());
    EXPECT_TRUE(nonbloppy::roundedAttributes(mesh, path("m.obj")).empty());
}

TEST_F(WriteMeshTest, RefusesAnAttributeWhoseValuesAreInTheArrayItsFlagDoesNotName)
{
    SurfaceMesh mesh = mixedMesh();
    nonbloppy::MeshAttribute id;
    id.name = "id";
    id.integer = true;
    id.integers.assign(mesh.points.size(), 7);
    id.values.assign(mesh.points.size(), 7.0f);
    mesh.attributes.push_back(id);
    EXPECT_EQ(messageOf<nonbloppy::ParameterError>([&] { writeMesh(mesh, path("m.ply")); }),
              "mesh attribute 'id' has float values but is marked integer (" + path("m.ply") + ")");
    mesh.attributes[0].integer = false;
    mesh.attributes[0].integers.assign(mesh.points.size(), 7);
    EXPECT_EQ(messageOf<nonbloppy::ParameterError>([&] { writeMesh(mesh, path("m.ply")); }),
              "mesh attribute 'id' has integers but is not marked integer (" + path("m.ply") + ")");
    EXPECT_TRUE(listDirectory(dir()).empty());
}

TEST_F(WriteMeshTest, RefusesMoreComponentsThanTheReadersTake)
{
    // The readers take up to 4096 components; a wider attribute made a file none read back.
    SurfaceMesh mesh = mixedMesh();
    nonbloppy::MeshAttribute wide;
    wide.name = "wide";
    wide.components = 4097;
    wide.values.assign(mesh.points.size() * 4097, 0.5f);
    mesh.attributes.push_back(wide);
    for (const std::string name : {"m.ply", "m.vtk"}) {
        EXPECT_EQ(messageOf<nonbloppy::ParameterError>([&] { writeMesh(mesh, path(name)); }),
                  "attribute 'wide' has 4097 components, more than the 4096 a file holds (" + path(name) + ")");
    }
    EXPECT_TRUE(listDirectory(dir()).empty());
    writeMesh(mesh, path("m.obj"));  // OBJ stores no attributes
    EXPECT_EQ(listDirectory(dir()), std::set<std::string>{"m.obj"});
}

TEST_F(WriteMeshTest, ObjTextIsExact)
{
    SurfaceMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {0.1f, 1, 0}, {1, 1, -2.5f}};
    mesh.quads = {{0, 1, 3, 2}};
    MeshWriteSettings keep;
    keep.keepQuads = true;
    writeMesh(mesh, path("q.obj"), keep);
    EXPECT_EQ(readBytes(path("q.obj")),
        "# nonbloppy surface mesh\nv 0 0 0\nv 1 0 0\nv 0.1 1 0\nv 1 1 -2.5\nf 1 2 4 3\n");
    writeMesh(mesh, path("t.obj"));
    EXPECT_EQ(readBytes(path("t.obj")),
        "# nonbloppy surface mesh\nv 0 0 0\nv 1 0 0\nv 0.1 1 0\nv 1 1 -2.5\nf 1 2 4\nf 1 4 3\n");

    mesh.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    writeMesh(mesh, path("n.obj"), keep);
    EXPECT_EQ(readBytes(path("n.obj")),
        "# nonbloppy surface mesh\nv 0 0 0\nv 1 0 0\nv 0.1 1 0\nv 1 1 -2.5\n"
        "vn 0 0 1\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 4//4 3//3\n");
}

TEST_F(WriteMeshTest, WrittenVtkIsAlsoAValidParticleFile)
{
    writeMesh(mixedMesh(), path("m.vtk"));
    const nonbloppy::ParticleSet particles = nonbloppy::readParticles(path("m.vtk"));
    ASSERT_EQ(particles.size(), 5u);
    EXPECT_EQ(particles.positions[1], mixedMesh().points[1]);
    ASSERT_NE(particles.findAttribute("normals"), nullptr);
    EXPECT_EQ(particles.findAttribute("normals")->asDouble(3, 1), double(0.8f));
}

TEST_F(WriteMeshTest, FailuresNameThePathAndLeaveNothingBehind)
{
    const std::string missing = path("missing/mesh.obj");
    EXPECT_EQ(messageOf<FileError>([&] { writeMesh(unitCube(), missing); }),
        "cannot write " + missing + ": No such file or directory");
    EXPECT_TRUE(listDirectory(dir()).empty());

    EXPECT_EQ(messageOf<FileError>([&] { writeMesh(unitCube(), path("mesh.stl")); }),
        "unknown mesh file extension '.stl' (" + path("mesh.stl") +
        "); expected .obj, .ply or .vtk");
    EXPECT_EQ(messageOf<FileError>([&] { readMesh(path("mesh.stl")); }),
        "unknown mesh file extension '.stl' (" + path("mesh.stl") +
        "); expected .obj, .ply or .vtk");
    EXPECT_TRUE(listDirectory(dir()).empty());

    SurfaceMesh broken = unitCube();
    broken.quads[5][2] = 8;
    EXPECT_EQ(messageOf<nonbloppy::ParameterError>([&] { writeMesh(broken, path("b.ply")); }),
        "polygon 5 references vertex 8 but the mesh has 8 vertices (" + path("b.ply") + ")");
    EXPECT_TRUE(listDirectory(dir()).empty());
    broken.quads[2][3] = 9;  // of two bad polygons, the first is named
    EXPECT_EQ(messageOf<nonbloppy::ParameterError>([&] { writeMesh(broken, path("b.ply")); }),
        "polygon 2 references vertex 9 but the mesh has 8 vertices (" + path("b.ply") + ")");
    EXPECT_TRUE(listDirectory(dir()).empty());

    EXPECT_FALSE(nonbloppy::isMeshFile("x.stl"));
    EXPECT_TRUE(nonbloppy::isMeshFile("x.Vtk"));
    // The same check, for callers that want it before the work; readMesh() makes it too.
    EXPECT_NO_THROW(nonbloppy::requireMeshFile("x.Vtk"));
    EXPECT_EQ(messageOf<FileError>([] { nonbloppy::requireMeshFile("out/mesh"); }),
              "mesh file name has no extension (out/mesh); expected .obj, .ply or .vtk");
    EXPECT_EQ(messageOf<FileError>([&] { readMesh(path("mesh")); }),
              "mesh file name has no extension (" + path("mesh") + "); expected .obj, .ply or .vtk");
    EXPECT_EQ(messageOf<FileError>([] { nonbloppy::requireParticleOutputFile("p.obj"); }),
              "unknown particle output extension '.obj' (p.obj); expected .ply, .vtk, .vtu, .xyz, .csv or .vdb");
    EXPECT_NO_THROW(nonbloppy::requireParticleOutputFile("p.VDB"));
}

TEST_F(WriteMeshTest, NewFilesGetTheUsualPermissions)
{
    // mkstemp() creates 0600 files; the renamed result must be readable like any new file.
    const mode_t mask = umask(022);
    umask(mask);
    writeMesh(unitCube(), path("cube.ply"));
    struct stat info;
    ASSERT_EQ(stat(path("cube.ply").c_str(), &info), 0);
    EXPECT_EQ(info.st_mode & 0777, 0666 & ~mask);
}

TEST_F(WriteMeshTest, AtomicFileRemovesItsTemporaryUnlessCommitted)
{
    const std::string target = path("out.vdb");
    writeBytes(target, "old");
    {
        nonbloppy::AtomicFile file(target);
        EXPECT_EQ(file.path(), target);
        EXPECT_EQ(file.tempPath().rfind(target + ".tmp-", 0), 0u);
        writeBytes(file.tempPath(), "new");
        EXPECT_EQ(listDirectory(dir()).size(), 2u);
    }  // not committed
    EXPECT_EQ(listDirectory(dir()), std::set<std::string>{"out.vdb"});
    EXPECT_EQ(readBytes(target), "old");

    {
        nonbloppy::AtomicFile file(target);
        writeBytes(file.tempPath(), "new");
        file.commit();
        EXPECT_TRUE(file.committed());
    }
    EXPECT_EQ(listDirectory(dir()), std::set<std::string>{"out.vdb"});
    EXPECT_EQ(readBytes(target), "new");

    // A writer that fails half-way leaves the old file as it was.
    EXPECT_EQ(messageOf<FileError>([&] {
        nonbloppy::writeFileAtomically(target, [](std::ostream& os) {
            os << "partial";
            throw std::runtime_error("disk on fire");
        });
    }), "cannot write " + target + ": disk on fire");
    EXPECT_EQ(readBytes(target), "new");
    EXPECT_EQ(listDirectory(dir()), std::set<std::string>{"out.vdb"});

    // nonbloppy errors (e.g. cancellation) pass through unchanged.
    EXPECT_EQ(messageOf<nonbloppy::CancelledError>([&] {
        nonbloppy::writeFileAtomically(target, [](std::ostream&) {
            throw nonbloppy::CancelledError("cancelled");
        });
    }), "cancelled");
    EXPECT_EQ(listDirectory(dir()), std::set<std::string>{"out.vdb"});

    nonbloppy::writeFileAtomically(target, [](std::ostream& os) { os << "newest"; });
    EXPECT_EQ(readBytes(target), "newest");
}

TEST_F(WriteMeshTest, WritingThroughASymlinkUpdatesItsTargetAndKeepsTheLink)
{
    namespace fs = std::filesystem;
    fs::create_directory(path("frames"));
    writeBytes(path("frames/0042.ply"), "old");
    // A chain: latest.ply -> current.ply -> frames/0042.ply, both relative.
    fs::create_symlink("frames/0042.ply", path("current.ply"));
    fs::create_symlink("current.ply", path("latest.ply"));
    const SurfaceMesh mesh = mixedMesh();
    writeMesh(mesh, path("latest.ply"));
    EXPECT_TRUE(fs::is_symlink(path("latest.ply")));
    EXPECT_TRUE(fs::is_symlink(path("current.ply")));
    EXPECT_EQ(fs::read_symlink(path("latest.ply")), "current.ply");
    writeMesh(mesh, path("direct.ply"));
    EXPECT_EQ(readBytes(path("frames/0042.ply")), readBytes(path("direct.ply")));
    EXPECT_EQ(listDirectory(path("frames")), std::set<std::string>{"0042.ply"});  // no temporary left

    // A dangling link gets its target created, as a shell's > would.
    fs::create_symlink("frames/0043.ply", path("next.ply"));
    writeMesh(mesh, path("next.ply"));
    EXPECT_TRUE(fs::is_symlink(path("next.ply")));
    EXPECT_EQ(readBytes(path("frames/0043.ply")), readBytes(path("direct.ply")));

    // A loop is an error naming the path given, and writes nothing.
    fs::create_symlink("loopB.ply", path("loopA.ply"));
    fs::create_symlink("loopA.ply", path("loopB.ply"));
    EXPECT_EQ(messageOf<FileError>([&] { writeMesh(mesh, path("loopA.ply")); }),
              "cannot write " + path("loopA.ply") + ": Too many levels of symbolic links");
    EXPECT_TRUE(fs::is_symlink(path("loopA.ply")));
}

TEST_F(WriteMeshTest, AFifoOrADirectoryInPlaceOfTheFileIsRefusedAndKept)
{
    // Renaming over a FIFO or device replaced the node itself: as root, through a link to
    // /dev/full, the system's /dev/full became a mesh file.
    namespace fs = std::filesystem;
    const SurfaceMesh mesh = mixedMesh();
    ASSERT_EQ(::mkfifo(path("pipe.ply").c_str(), 0644), 0);
    fs::create_symlink("pipe.ply", path("link.ply"));
    fs::create_directory(path("dir.ply"));
    EXPECT_EQ(messageOf<FileError>([&] { writeMesh(mesh, path("pipe.ply")); }),
              "cannot write " + path("pipe.ply") + ": not a regular file");
    EXPECT_EQ(messageOf<FileError>([&] { writeMesh(mesh, path("link.ply")); }),
              "cannot write " + path("link.ply") + ": not a regular file");
    EXPECT_EQ(messageOf<FileError>([&] { writeMesh(mesh, path("dir.ply")); }),
              "cannot write " + path("dir.ply") + ": Is a directory");
    EXPECT_TRUE(fs::is_fifo(path("pipe.ply")));
    EXPECT_TRUE(fs::is_symlink(path("link.ply")));
    EXPECT_TRUE(fs::is_directory(path("dir.ply")));
    EXPECT_EQ(listDirectory(dir()), (std::set<std::string>{"dir.ply", "link.ply", "pipe.ply"}));
}

TEST_F(WriteMeshTest, NamesUpToTheFileSystemLimitCanBeWritten)
{
    // 255 bytes is ext4's and tmpfs's limit; "name.tmp-XXXXXX" would exceed it from 245 on.
    const SurfaceMesh mesh = mixedMesh();
    writeMesh(mesh, path("short.ply"));
    for (size_t length : {size_t(244), size_t(245), size_t(255)}) {
        const std::string name = std::string(length - 4, 'm') + ".ply";
        writeMesh(mesh, path(name));
        EXPECT_EQ(readBytes(path(name)), readBytes(path("short.ply"))) << length;
        EXPECT_EQ(listDirectory(dir()).count(name), 1u);
        std::filesystem::remove(path(name));
        {
            nonbloppy::AtomicFile file(path(name));  // the temporary file's name, not committed
            const std::string temp = file.tempPath().substr(dir().size() + 1);
            EXPECT_LE(temp.size(), 255u);
            EXPECT_NE(temp.find(".tmp-"), std::string::npos) << temp;  // found by the *.tmp-* cleanup
        }
    }
    EXPECT_EQ(listDirectory(dir()), std::set<std::string>{"short.ply"});
}

TEST_F(WriteMeshTest, LargeFilesGoPastThePageCacheWithTheSameBytes)
{
    // Sizes around the direct writer's edges: exactly the threshold, whole 4 KiB blocks past
    // one 4 MiB buffer, and partial last blocks after one and two full buffers.
    // Elsewhere (tmpfs, overlayfs) both ways would be the page cache's: nothing to compare.
    if (!nonbloppy::directIoSuitable(dir())) GTEST_SKIP() << "no direct I/O on " << dir();
    std::mt19937 random(7);
    size_t index = 0;
    for (const size_t size : {nonbloppy::kDirectIoMinBytes, (size_t(4) << 20) + 4096,
                              (size_t(2) << 20) + 1, (size_t(9) << 20) + 123}) {
        std::string bytes(size, '\0');
        for (char& b : bytes) b = char(random());
        const std::string target = path("large" + std::to_string(index++) + ".bin");
        // Written in uneven pieces: a 1000-byte write, a single character, then the rest.
        const bool direct = nonbloppy::writeFileAtomically(target, [&](std::ostream& os) {
            os.write(bytes.data(), 1000);
            os.put(bytes[1000]);
            os.write(bytes.data() + 1001, std::streamsize(size - 1001));
        }, size);
        EXPECT_TRUE(direct) << size;
        EXPECT_TRUE(readBytes(target) == bytes) << size;
    }
    // Small or unknown sizes always go through the page cache.
    EXPECT_FALSE(nonbloppy::writeFileAtomically(path("small.bin"), [](std::ostream& os) { os << "x"; }, 100));
    EXPECT_FALSE(nonbloppy::writeFileAtomically(path("unknown.bin"), [](std::ostream& os) { os << "y"; }));
    EXPECT_EQ(readBytes(path("small.bin")), "x");
    // Only the targets remain: no temporary files.
    EXPECT_EQ(listDirectory(dir()).size(), 6u);
}

/// For its lifetime, a file-size limit of @a bytes with SIGXFSZ ignored: writes past it fail
/// with EFBIG, a stand-in for a full disk that needs no file system of its own.
class FileSizeLimit
{
public:
    explicit FileSizeLimit(rlim_t bytes)
    {
        mSet = getrlimit(RLIMIT_FSIZE, &mSaved) == 0;
        mOldHandler = std::signal(SIGXFSZ, SIG_IGN);
        struct rlimit limited = mSaved;
        limited.rlim_cur = bytes;
        mSet = mSet && setrlimit(RLIMIT_FSIZE, &limited) == 0;
    }
    ~FileSizeLimit()
    {
        setrlimit(RLIMIT_FSIZE, &mSaved);
        std::signal(SIGXFSZ, mOldHandler);
    }
    FileSizeLimit(const FileSizeLimit&) = delete;
    FileSizeLimit& operator=(const FileSizeLimit&) = delete;
    bool set() const { return mSet; }

private:
    struct rlimit mSaved{};
    void (*mOldHandler)(int) = SIG_DFL;
    bool mSet = false;
};

TEST_F(WriteMeshTest, AWriteThatFailsInATaskReportsItsOwnError)
{
    // The writers hand their batches to the stream from TBB tasks, and errno is per thread:
    // a full disk was reported as "Input/output error" whenever the failing write ran on a
    // worker (half the runs at two threads; hostile-input audit). A 1 MB file-size limit
    // (SIGXFSZ ignored) fails every format's write with EFBIG, on whichever thread, through
    // the page cache and with direct I/O; each time the caller must say so and leave nothing.
    const SurfaceMesh mesh = randomMesh(11, 10.0f, 200000, 300000, 0);
    std::vector<std::string> messages, expected;
    {
        const FileSizeLimit limit(1u << 20);
        ASSERT_TRUE(limit.set());
        for (int round = 0; round < 4; ++round) {
            for (const char* name : {"m.obj", "m.ply", "m.vtk"}) {
                for (const bool directIo : {false, true}) {
                    MeshWriteSettings settings;
                    settings.directIo = directIo;
                    const std::string target = path(name);
                    messages.push_back(messageOf<nonbloppy::FileError>([&] { nonbloppy::writeMesh(mesh, target, settings); }));
                    expected.push_back("cannot write " + target + ": File too large");
                }
            }
        }
    }
    EXPECT_EQ(messages, expected);
    EXPECT_TRUE(listDirectory(dir()).empty());
}

TEST_F(WriteMeshTest, ADirectWriteThatFailsInTheWriterThreadFailsTheFile)
{
    if (!nonbloppy::directIoSuitable(dir())) GTEST_SKIP() << "no direct I/O on " << dir();
    // A 6 MB file-size limit stands in for a full disk: the second 4 MiB buffer, written by
    // the writer thread while the caller fills the third, fails with EFBIG (SIGXFSZ
    // ignored). The error must reach the caller, and nothing may be left.
    const std::string target = path("full.bin");
    const std::string bytes((size_t(13) << 20) + 5, 'x');
    std::string message;
    {
        const FileSizeLimit limit(6u << 20);
        ASSERT_TRUE(limit.set());
        try {
            nonbloppy::writeFileAtomically(target, [&](std::ostream& os) {
                for (size_t at = 0; at < bytes.size(); at += 100000) {
                    os.write(bytes.data() + at, std::streamsize(std::min<size_t>(100000, bytes.size() - at)));
                }
            }, bytes.size());
        } catch (const nonbloppy::FileError& e) {
            message = e.what();
        }
    }
    EXPECT_EQ(message, "cannot write " + target + ": File too large");
    EXPECT_TRUE(listDirectory(dir()).empty());
}

TEST_F(WriteMeshTest, DirectIoSettingDoesNotChangeTheFile)
{
    // A 300 x 300 grid of quads: 1.1 MB of positions and normals, over the threshold.
    SurfaceMesh grid;
    const uint32_t n = 300;
    for (uint32_t i = 0; i < n; ++i) {
        for (uint32_t j = 0; j < n; ++j) {
            grid.points.emplace_back(0.01f * float(i), 0.01f * float(j), 0.001f * float((i * j) % 7));
            grid.normals.emplace_back(0.0f, 0.0f, 1.0f);
        }
    }
    for (uint32_t i = 0; i + 1 < n; ++i) {
        for (uint32_t j = 0; j + 1 < n; ++j) {
            grid.quads.emplace_back(i * n + j, (i + 1) * n + j, (i + 1) * n + j + 1, i * n + j + 1);
        }
    }
    if (!nonbloppy::directIoSuitable(dir())) GTEST_SKIP() << "no direct I/O on " << dir();
    for (const char* ext : {".ply", ".vtk", ".obj"}) {
        MeshWriteSettings settings;
        settings.directIo = true;
        writeMesh(grid, path(std::string("direct") + ext), settings);
        settings.directIo = false;
        writeMesh(grid, path(std::string("cached") + ext), settings);
        const std::string direct = readBytes(path(std::string("direct") + ext));
        EXPECT_GT(direct.size(), nonbloppy::kDirectIoMinBytes) << ext;
        EXPECT_TRUE(direct == readBytes(path(std::string("cached") + ext))) << ext;
    }
}

// ------------------------------------------------------------------------------------------
// readMesh on files from other writers

TEST_F(WriteMeshTest, ReadObjWithEveryCornerFormAndNegativeIndices)
{
    writeBytes(path("forms.obj"),
        "# comment\nmtllib x.mtl\no thing\n"
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\n"
        "vt 0 0\nvt 1 0\nvt 1 1\n"
        "vn 0 0 1\nvn 0 0 -1\n"
        "s off\nusemtl red\n"
        "f 1 2 3\n"                    // v
        "f 1/1 3/2 4/3\n"              // v/vt
        "f -5//2 -4//2 -3//2 -2//2\n"  // v//vn with negative indices
        "f 1/1/1 2/2/1 3/3/1 5/1/1 4/2/1\r\n");  // v/vt/vn pentagon, CRLF
    const SurfaceMesh mesh = readMesh(path("forms.obj"));
    ASSERT_EQ(mesh.points.size(), 5u);
    EXPECT_EQ(mesh.points[4], openvdb::Vec3s(0.5f, 1.5f, 0));
    const std::vector<openvdb::Vec3I> triangles = {
        {0, 1, 2}, {0, 2, 3}, {0, 1, 2}, {0, 2, 4}, {0, 4, 3}};
    EXPECT_EQ(mesh.triangles, triangles);
    EXPECT_EQ(mesh.quads, std::vector<openvdb::Vec4I>{openvdb::Vec4I(0, 1, 2, 3)});
    // Normals are per corner in OBJ; the last corner to name a vertex wins.
    ASSERT_EQ(mesh.normals.size(), 5u);
    EXPECT_EQ(mesh.normals[0], openvdb::Vec3s(0, 0, 1));
    EXPECT_EQ(mesh.normals[4], openvdb::Vec3s(0, 0, 1));

    // An index past the last vertex: the line and the index as written (1-based), not the
    // polygon's number. Vertices may still follow the face that names them.
    writeBytes(path("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\n# a comment\nf 1 2 4\nf 1 2 3\n");
    EXPECT_EQ(messageOf<FileError>([&] { readMesh(path("bad.obj")); }),
        "vertex index 4 out of range (the file has 3 vertices) at line 5 (" + path("bad.obj") + ")");
    writeBytes(path("ahead.obj"), "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    EXPECT_EQ(readMesh(path("ahead.obj")).triangles, std::vector<openvdb::Vec3I>{openvdb::Vec3I(0, 1, 2)});
    writeBytes(path("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n");
    EXPECT_EQ(messageOf<FileError>([&] { readMesh(path("bad.obj")); }),
        "bad vertex index 'x' at line 4 (" + path("bad.obj") + ")");
    writeBytes(path("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n");
    EXPECT_EQ(messageOf<FileError>([&] { readMesh(path("bad.obj")); }),
        "face with 2 vertices (at least 3) at line 5 (" + path("bad.obj") + ")");
    writeBytes(path("bad.obj"), "v 0 0 0\nf\t\r\n");
    EXPECT_EQ(messageOf<FileError>([&] { readMesh(path("bad.obj")); }),
        "face with 0 vertices (at least 3) at line 2 (" + path("bad.obj") + ")");
    writeBytes(path("bad.obj"), "v 0 0\n");
    EXPECT_EQ(messageOf<FileError>([&] { readMesh(path("bad.obj")); }),
        "expected three coordinates at line 1 (" + path("bad.obj") + ")");
    EXPECT_EQ(messageOf<FileError>([&] { readMesh(path("none.obj")); }),
        "cannot open " + path("none.obj") + ": No such file or directory");
    // Another kind of file named .obj (a PNG; its NUL is on line 4) read as an empty mesh:
    // its lines matched no statement.
    writeBytes(path("bad.obj"), std::string("v 0 0 0\n\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 21));
    EXPECT_EQ(messageOf<FileError>([&] { readMesh(path("bad.obj")); }),
        "binary data, not OBJ text, at line 4 (" + path("bad.obj") + ")");
    // An empty OBJ file is an empty mesh, as writeMesh() writes one.
    writeBytes(path("empty.obj"), "");
    EXPECT_TRUE(readMesh(path("empty.obj")).points.empty());
}

TEST_F(WriteMeshTest, ReadAsciiPlyAndVtkMeshes)
{
    writeBytes(path("a.ply"),
        "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
        "property float z\nproperty uchar red\nelement face 2\n"
        "property uchar flags\nproperty list uchar uint vertex_indices\nend_header\n"
        "0 0 0 1\n1 0 0 2\n1 1 0 3\n0 1 0 4\n0.5 2 0 5\n"
        "7 4 0 1 2 3\n7 5 0 1 2 4 3\n");
    SurfaceMesh mesh = readMesh(path("a.ply"));
    EXPECT_EQ(mesh.points.size(), 5u);
    EXPECT_TRUE(mesh.normals.empty());
    EXPECT_EQ(mesh.quads, std::vector<openvdb::Vec4I>{openvdb::Vec4I(0, 1, 2, 3)});
    EXPECT_EQ(mesh.triangles.size(), 3u);

    writeBytes(path("a.vtk"),
        "# vtk DataFile Version 3.0\nmesh\nASCII\nDATASET POLYDATA\n"
        "POINTS 4 float\n0 0 0 1 0 0 1 1 0 0 1 0\n"
        "LINES 1 3\n2 0 1\n"
        "POLYGONS 2 7\n3 0 1 2\n2 0 2\n");
    EXPECT_EQ(messageOf<FileError>([&] { readMesh(path("a.vtk")); }),
        "polygon 1 has only 2 vertices (" + path("a.vtk") + ")");
    writeBytes(path("a.vtk"),
        "# vtk DataFile Version 3.0\nmesh\nASCII\nDATASET POLYDATA\n"
        "POINTS 4 float\n0 0 0 1 0 0 1 1 0 0 1 0\n"
        "LINES 1 3\n2 0 1\n"
        "POLYGONS 2 9\n3 0 1 2\n4 0 1 2 3\n"
        "POINT_DATA 4\nNORMALS n float\n0 0 1 0 0 1 0 0 1 0 0 1\n");
    mesh = readMesh(path("a.vtk"));
    EXPECT_EQ(mesh.triangles, std::vector<openvdb::Vec3I>{openvdb::Vec3I(0, 1, 2)});
    EXPECT_EQ(mesh.quads, std::vector<openvdb::Vec4I>{openvdb::Vec4I(0, 1, 2, 3)});
    ASSERT_EQ(mesh.normals.size(), 4u);
    EXPECT_EQ(mesh.normals[3], openvdb::Vec3s(0, 0, 1));

    writeBytes(path("b.vtk"),
        "# vtk DataFile Version 3.0\nmesh\nASCII\nDATASET POLYDATA\n"
        "POINTS 3 float\n0 0 0 1 0 0 1 1 0\nPOLYGONS 1 4\n3 0 1 7\n");
    EXPECT_EQ(messageOf<FileError>([&] { readMesh(path("b.vtk")); }),
        "polygon 0 references vertex 7 but the file has 3 vertices (" + path("b.vtk") + ")");
}

TEST_F(WriteMeshTest, TruncatedMeshFilesAreFileErrors)
{
    const SurfaceMesh mesh = mixedMesh();
    for (const char* ext : {".ply", ".vtk"}) {
        const std::string full = path(std::string("full") + ext);
        writeMesh(mesh, full);
        const std::string bytes = readBytes(full);
        const std::string cut = path(std::string("cut") + ext);
        size_t failures = 0;
        for (size_t k = 0; k + 1 < bytes.size(); ++k) {
            writeBytes(cut, bytes.substr(0, k));
            try {
                readMesh(cut);
            } catch (const FileError& e) {
                EXPECT_NE(std::string(e.what()).find("(" + cut + ")"), std::string::npos);
                ++failures;
            }
        }
        // Only cuts at the very end of the faces / before POINT_DATA can still parse.
        EXPECT_GT(failures, bytes.size() - 10) << ext;
    }
}

TEST_F(WriteMeshTest, MeshFilesDeclareTheirPolygonsHoweverBrokenTheRestIs)
{
    const SurfaceMesh mesh = mixedMesh();
    for (const char* ext : {".ply", ".vtk"}) {
        const std::string full = path(std::string("full") + ext);
        writeMesh(mesh, full);
        EXPECT_TRUE(declaresPolygons(full)) << ext;
        const std::string bytes = readBytes(full);
        // The declaration is the PLY header's last line, or the VTK POLYGONS header line:
        // cut before it, the file is not a mesh; cut after it (its newline may go), it is,
        // however little of the rest is there. Cuts inside the line go either way.
        const std::string marker = std::string(ext) == ".ply" ? "end_header\n" : "POLYGONS ";
        const size_t lineStart = bytes.find(marker);
        ASSERT_NE(lineStart, std::string::npos) << ext;
        const size_t lineEnd = bytes.find('\n', lineStart);
        const std::string cut = path(std::string("cut") + ext);
        for (size_t k = 0; k < bytes.size(); k += (k < lineEnd + 64 ? 1 : 97)) {
            if (k > lineStart && k < lineEnd) continue;
            writeBytes(cut, bytes.substr(0, k));
            EXPECT_EQ(declaresPolygons(cut), k >= lineEnd) << ext << " cut at " << k << " of " << bytes.size();
        }
    }
    EXPECT_TRUE(declaresPolygons(path("full.ply")));
    writeMesh(mesh, path("m.obj"));
    EXPECT_TRUE(declaresPolygons(path("m.obj")));
    // Particle files of the same formats, and a PLY whose face element is empty.
    EXPECT_FALSE(declaresPolygons(dataPath("cube_8_particles.vtk")));
    EXPECT_FALSE(declaresPolygons(dataPath("cube_8_particles.vtu")));
    writeBytes(path("noFaces.ply"), "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                    "property float z\nelement face 0\nproperty list uchar int vertex_indices\n"
                                    "end_header\n0 0 0\n");
    EXPECT_FALSE(declaresPolygons(path("noFaces.ply")));
    // An empty mesh is a mesh (and an empty VTK particle file is not).
    for (const char* ext : {".ply", ".vtk"}) {
        const std::string empty = path(std::string("empty") + ext);
        writeMesh(SurfaceMesh(), empty);
        EXPECT_TRUE(declaresPolygons(empty)) << ext;
        EXPECT_EQ(readMesh(empty).points.size(), 0u) << ext;
    }
    writeBytes(path("noPoints.vtk"), "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 0 float\n");
    EXPECT_FALSE(declaresPolygons(path("noPoints.vtk")));
    writeBytes(path("emptyCells.vtk"), "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 1 float\n0 0 0\n"
                                       "POLYGONS 0 0\n");
    EXPECT_FALSE(declaresPolygons(path("emptyCells.vtk")));
    EXPECT_EQ(messageOf<FileError>([&] { declaresPolygons(path("missing.ply")); }).rfind("cannot open ", 0), 0u);
    // A missing OBJ file was declared a mesh.
    EXPECT_EQ(messageOf<FileError>([&] { declaresPolygons(path("missing.obj")); }),
              "cannot open " + path("missing.obj") + ": No such file or directory");
}

TEST_F(WriteMeshTest, MeasuresSurviveARoundTrip)
{
    const SurfaceMesh cube = unitCube();
    for (const char* ext : {".obj", ".ply", ".vtk"}) {
        writeMesh(cube, path(std::string("c") + ext));
        const nonbloppy::MeshMeasures m = nonbloppy::measureMesh(readMesh(path(std::string("c") + ext)));
        EXPECT_TRUE(m.closed && m.manifold) << ext;
        EXPECT_DOUBLE_EQ(m.volume, 1.0) << ext;
        EXPECT_EQ(m.polygons, 12u) << ext;  // quads split by default
    }
}

} // namespace
