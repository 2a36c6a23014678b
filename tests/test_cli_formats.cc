// SPDX-License-Identifier: Apache-2.0
// CLI tests for issue 5: `nonbloppy convert` round trips between every particle writer and
// the readers, `mesh --attributes` (PLY/VTK vertex data, OBJ warning), and the extra grids
// --vdb-surface and --vdb-points.

#include <nonbloppy/Error.h>
#include <nonbloppy/ReadMesh.h>
#include <nonbloppy/ReadParticles.h>
#include <nonbloppy/Version.h>
#include <nonbloppy/WriteParticles.h>

#include <openvdb/openvdb.h>
#include <openvdb/points/PointCount.h>
#include <openvdb/points/PointDataGrid.h>
#include <openvdb/tools/Interpolation.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "../src/AtomicFile.h"
#include "CliTestUtil.h"
#include "TestUtil.h"
#include "support/OpenVdbPoints.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace nonbloppy_test;
using nonbloppy::ParticleAttribute;
using nonbloppy::ParticleSet;

const std::string kData = NONBLOPPY_TEST_DATA_DIR;

class CliFormatsTest : public CliFixture
{
protected:
    std::string path(const std::string& name) const { return dir() + "/" + name; }
};

/// The values of attribute @a name (component @a c) per particle, keyed by the "id"
/// attribute, so files that reorder the particles (VDB points) can be compared.
std::map<int64_t, std::vector<double>> byId(const ParticleSet& particles)
{
    std::map<int64_t, std::vector<double>> rows;
    const ParticleAttribute* id = particles.findAttribute("id");
    if (!id) throw std::runtime_error("no id");
    for (size_t n = 0; n < particles.size(); ++n) {
        std::vector<double>& row = rows[int64_t(id->asDouble(n))];
        for (int a = 0; a < 3; ++a) row.push_back(particles.positions[n][a]);
        for (const ParticleAttribute& attribute : particles.attributes) {
            if (attribute.name == "id") continue;
            for (int c = 0; c < attribute.components; ++c) row.push_back(float(attribute.asDouble(n, c)));
        }
    }
    return rows;
}

TEST_F(CliFormatsTest, ConvertRoundTripsThroughEveryWriter)
{
    const std::string source = kData + "/dam_break_frame_9_6859_particles.bgeo";
    const ParticleSet original = nonbloppy::readParticles(source);
    const auto expected = byId(original);
    ASSERT_EQ(expected.size(), 6859u);
    for (const std::string ext : {"vtk", "vtu", "csv", "vdb", "ply"}) {
        SCOPED_TRACE(ext);
        const std::string file = path("frame." + ext);
        const RunResult r = run("convert " + quote(source) + " " + quote(file));
        ASSERT_EQ(r.exitCode, 0) << r.err;
        EXPECT_EQ(r.out, "converted 6859 particles with 3 attributes: " + source + " -> " + file + "\n");
        const ParticleSet back = nonbloppy::readParticles(file);
        ASSERT_EQ(back.size(), original.size());
        ASSERT_EQ(back.attributes.size(), 3u);
        EXPECT_EQ(back.findAttribute("velocity")->components, 3);
        const auto actual = byId(back);
        ASSERT_EQ(actual.size(), expected.size());
        for (const auto& [id, row] : expected) {
            const std::vector<double>& got = actual.at(id);
            ASSERT_EQ(got.size(), row.size());
            for (size_t k = 0; k < row.size(); ++k) {
                if (ext == "vdb" && k < 3) {
                    ASSERT_NEAR(got[k], row[k], 1e-5) << "id " << id;  // voxel-relative offsets
                } else {
                    ASSERT_EQ(got[k], row[k]) << "id " << id << " value " << k;
                }
            }
        }
    }
    // PLY writes velocity as properties velocity_x/_y/_z, which read back as the vector.
    const std::string plyText = readText(path("frame.ply"));
    for (const char* property : {" velocity_x\n", " velocity_y\n", " velocity_z\n"}) {
        EXPECT_NE(plyText.find(property), std::string::npos) << property;
    }
    // A chain through three formats ends where it began.
    ASSERT_EQ(run("convert " + quote(path("frame.vtu")) + " " + quote(path("chain.csv"))).exitCode, 0);
    ASSERT_EQ(run("convert " + quote(path("chain.csv")) + " " + quote(path("chain.vtk"))).exitCode, 0);
    const ParticleSet chain = nonbloppy::readParticles(path("chain.vtk"));
    ASSERT_EQ(chain.size(), original.size());
    for (size_t n = 0; n < chain.size(); ++n) ASSERT_EQ(chain.positions[n], original.positions[n]);
}

TEST_F(CliFormatsTest, ConvertToXyzWarnsAndErrorsAreOneLine)
{
    const std::string source = kData + "/fluid_250_particles.vtu";
    const RunResult r = run("convert -q " + quote(source) + " " + quote(path("p.xyz")));
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_EQ(r.out, "");
    EXPECT_EQ(r.err, "nonbloppy: warning: .xyz holds positions only; attributes dropped: velocity, "
                     "pressure, density, index\n");
    const ParticleSet xyz = nonbloppy::readParticles(path("p.xyz"));
    const ParticleSet vtu = nonbloppy::readParticles(source);
    ASSERT_EQ(xyz.size(), 250u);
    for (size_t n = 0; n < 250; ++n) EXPECT_EQ(xyz.positions[n], vtu.positions[n]);
    // Without -q the summary counts what was written (it said "with 4 attributes").
    const RunResult loud = run("convert " + quote(source) + " " + quote(path("q.xyz")));
    EXPECT_EQ(loud.out, "converted 250 particles with 0 attributes: " + source + " -> " + path("q.xyz") + "\n");

    RunResult bad = run("convert " + quote(source) + " " + quote(path("p.obj")));
    EXPECT_EQ(bad.exitCode, 2);
    EXPECT_EQ(bad.err, "nonbloppy: unknown particle output extension '.obj' (" + path("p.obj") +
                       "); expected .ply, .vtk, .vtu, .xyz, .csv or .vdb\n");
    bad = run("convert " + quote(source) + " " + quote(source));
    EXPECT_EQ(bad.exitCode, 2);
    EXPECT_EQ(bad.err, "nonbloppy: cannot write " + source + ": it is the input file\n");
    const std::string density = path("density.vdb");
    ASSERT_EQ(run("mesh " + quote(source) + " -q -o " + quote(path("m.ply")) + " --vdb " + quote(density)).exitCode, 0);
    bad = run("convert " + quote(density) + " " + quote(path("p.csv")));
    EXPECT_EQ(bad.exitCode, 1);
    EXPECT_EQ(bad.err, "nonbloppy: no PointDataGrid in this .vdb file (grids: density float); a density "
                       "cache holds no particles to read (" + density + ")\n");
    EXPECT_FALSE(fs::exists(path("p.csv")));
}

TEST_F(CliFormatsTest, LargeParticleFilesAreTheSameWithAndWithoutDirectIo)
{
    // 120,000 particles: 1.4 MB of positions, past the 1 MiB from which files may bypass the
    // page cache. Every writer gives the same bytes either way, as does `convert --no-direct-io`.
    ParticleSet particles;
    ParticleAttribute speed;  // Float32, one component
    speed.name = "speed";
    for (int n = 0; n < 120000; ++n) {
        particles.positions.emplace_back(0.01f * float(n % 97), 0.02f * float(n % 89), 0.001f * float(n));
        const float value = 0.5f * float(n % 13);
        const auto* bytes = reinterpret_cast<const unsigned char*>(&value);
        speed.bytes.insert(speed.bytes.end(), bytes, bytes + sizeof(value));
    }
    particles.attributes.push_back(speed);
    // Elsewhere (tmpfs, overlayfs) both ways would be the page cache's: nothing to compare.
    if (!nonbloppy::directIoSuitable(dir())) GTEST_SKIP() << "no direct I/O on " << dir();
    for (const std::string ext : {"ply", "vtk", "vtu", "xyz", "csv"}) {
        nonbloppy::ParticleWriteSettings cached;
        cached.directIo = false;
        nonbloppy::writeParticles(particles, path("direct." + ext));
        nonbloppy::writeParticles(particles, path("cached." + ext), cached);
        const std::string direct = readText(path("direct." + ext));
        EXPECT_GT(direct.size(), size_t(1) << 20) << ext;
        EXPECT_TRUE(direct == readText(path("cached." + ext))) << ext << " files differ";
    }
    const RunResult viaCache = run("convert -q --no-direct-io " + quote(path("direct.ply")) + " " + quote(path("c.vtk")));
    ASSERT_EQ(viaCache.exitCode, 0) << viaCache.err;
    ASSERT_EQ(run("convert -q " + quote(path("direct.ply")) + " " + quote(path("d.vtk"))).exitCode, 0);
    EXPECT_TRUE(readText(path("c.vtk")) == readText(path("direct.vtk")));
    EXPECT_TRUE(readText(path("d.vtk")) == readText(path("direct.vtk")));
    EXPECT_NE(run("convert --help").out.find("--no-direct-io"), std::string::npos);
}

TEST_F(CliFormatsTest, MeshAttributesReachPlyAndVtk)
{
    const std::string source = kData + "/fluid_250_particles.vtu";
    for (const std::string ext : {"ply", "vtk"}) {
        const std::string mesh = path("m." + ext);
        const RunResult r = run("mesh -q " + quote(source) + " -o " + quote(mesh) +
                                " --attributes velocity,pressure");
        ASSERT_EQ(r.exitCode, 0) << r.err;
        EXPECT_EQ(r.err, "");
        const nonbloppy::SurfaceMesh polygons = nonbloppy::readMesh(mesh);
        const ParticleSet vertices = nonbloppy::readParticles(mesh);
        ASSERT_GT(polygons.points.size(), 100u);
        ASSERT_EQ(vertices.size(), polygons.points.size());
        for (const std::string name : {"velocity", "pressure"}) {
            const ParticleAttribute* a = vertices.findAttribute(name);
            ASSERT_NE(a, nullptr) << name;
            EXPECT_EQ(a->size(), vertices.size());
            EXPECT_EQ(a->components, name == "velocity" ? 3 : 1);
        }
        // Pressure is non-negative on every particle, so its weighted mean is too, and not
        // zero everywhere.
        const ParticleAttribute* pressure = vertices.findAttribute("pressure");
        double maxPressure = 0;
        for (size_t i = 0; i < vertices.size(); ++i) {
            ASSERT_GE(pressure->asDouble(i), 0.0);
            maxPressure = std::max(maxPressure, pressure->asDouble(i));
        }
        EXPECT_GT(maxPressure, 0.0);
        // inspect lists them (not the normals), as it lists a particle file's.
        const RunResult shown = run("inspect " + quote(mesh));
        ASSERT_EQ(shown.exitCode, 0) << shown.err;
        EXPECT_NE(shown.out.find("\n  attributes       velocity  float32 x3  x "), std::string::npos) << shown.out;
        EXPECT_NE(shown.out.find("\n                   pressure  float32  0 .. "), std::string::npos) << shown.out;
        const RunResult json = run("inspect --json " + quote(mesh));
        ASSERT_EQ(json.exitCode, 0) << json.err;
        nlohmann::json report = nlohmann::json::parse(json.out);
        ASSERT_EQ(report.at("attributes").size(), 2u) << json.out;
        for (const char* key : {"min", "max", "non_finite"}) report["attributes"][0].erase(key);
        EXPECT_EQ(report["attributes"][0], (nlohmann::json{{"name", "velocity"}, {"type", "float32"}, {"components", 3}}));
        // The vertices' pressure range, as the particle reader sees the file's values.
        EXPECT_EQ(report["attributes"][1]["max"][0].get<float>(), float(maxPressure));
        EXPECT_EQ(report["attributes"][1]["non_finite"], 0);
        for (const char* key : {"min", "max", "non_finite"}) report["attributes"][1].erase(key);
        EXPECT_EQ(report["attributes"][1], (nlohmann::json{{"name", "pressure"}, {"type", "float32"}, {"components", 1}}));
    }
    const RunResult obj = run("mesh -q " + quote(source) + " -o " + quote(path("m.obj")) + " --attributes all");
    EXPECT_EQ(obj.exitCode, 0);
    EXPECT_EQ(obj.err, "nonbloppy: warning: OBJ cannot store vertex attributes; write .ply or .vtk "
                       "to keep --attributes\n");
    // Refused once the file is read, before it is meshed (-v lists the stages that ran).
    const RunResult unknown = run("mesh -v " + quote(source) + " -o " + quote(path("u.ply")) + " --attributes speed");
    EXPECT_EQ(unknown.exitCode, 1);
    EXPECT_EQ(lines(unknown.err).back(), "nonbloppy: " + source + ": unknown attribute 'speed'; the particles "
                                         "have: velocity, pressure, density, index");
    EXPECT_EQ(unknown.err.find("rasterize density"), std::string::npos) << unknown.err;
    EXPECT_FALSE(fs::exists(path("u.ply")));
    // A list without a name is a usage error, before anything is read.
    for (const std::string list : {"", " , "}) {
        const RunResult none = run("mesh -q " + quote(source) + " -o " + quote(path("u.ply")) + " --attributes " + quote(list));
        EXPECT_EQ(none.exitCode, 2) << list;
        EXPECT_EQ(none.err, "nonbloppy: --attributes names no attribute, got '" + list + "'\n");
    }
}

TEST_F(CliFormatsTest, AttributeNamesKeepTheirInnerSpaces)
{
    // --attributes dropped every space: 'my attr' was looked up as 'myattr' and refused.
    const ParticleSet cube = nonbloppy::readParticles(kData + "/cube_2366_particles.vtk");
    std::string csv = "x,y,z,my attr,other\n";
    for (size_t i = 0; i < cube.size(); ++i) {
        csv += std::to_string(cube.positions[i].x()) + "," + std::to_string(cube.positions[i].y()) + ","
               + std::to_string(cube.positions[i].z()) + ",2.5," + std::to_string(i) + "\n";
    }
    writeText(path("spaced.csv"), csv);
    const RunResult r = run("mesh -q " + quote(path("spaced.csv")) + " -o " + quote(path("m.ply"))
                            + " --attributes ' my attr , other'");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const ParticleSet vertices = nonbloppy::readParticles(path("m.ply"));
    const ParticleAttribute* mine = vertices.findAttribute("my_attr");  // a PLY name is one word
    ASSERT_NE(mine, nullptr);
    EXPECT_EQ(mine->asDouble(0), 2.5);
    EXPECT_NE(vertices.findAttribute("other"), nullptr);
    const RunResult joined = run("mesh -q " + quote(path("spaced.csv")) + " -o " + quote(path("u.ply"))
                                 + " --attributes myattr");
    EXPECT_EQ(joined.exitCode, 1);
    EXPECT_EQ(joined.err, "nonbloppy: " + path("spaced.csv") + ": unknown attribute 'myattr'; the particles have: "
                          "my attr, other\n");
    // --vdb-points says what it renames, as convert does (it said nothing).
    const RunResult points = run("mesh -q " + quote(path("spaced.csv")) + " -o " + quote(path("p.ply")) + " --vdb "
                                 + quote(path("p.vdb")) + " --vdb-points");
    ASSERT_EQ(points.exitCode, 0) << points.err;
    EXPECT_EQ(points.err, "nonbloppy: warning: attribute 'my attr' is written to " + path("p.vdb") + " as 'my_attr'\n");
}

TEST_F(CliFormatsTest, IntegerAttributesReachTheMeshAsTheNearestParticlesValue)
{
    // The int64 "index" of each vertex is that of the nearest particle, not a mean of several.
    const std::string source = kData + "/fluid_250_particles.vtu";
    const RunResult r = run("mesh -q " + quote(source) + " -o " + quote(path("m.ply")) + " --radius 0.3 --attributes index");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err, "");
    const ParticleSet vertices = nonbloppy::readParticles(path("m.ply"));
    const ParticleSet particles = nonbloppy::readParticles(source);
    const ParticleAttribute* index = vertices.findAttribute("index");
    ASSERT_NE(index, nullptr);
    EXPECT_EQ(index->type, nonbloppy::ScalarType::Int32);  // "property int index"
    ASSERT_GT(vertices.size(), 100u);
    std::vector<size_t> nearestOf(vertices.size());
    for (size_t i = 0; i < vertices.size(); ++i) {
        size_t nearest = 0;
        for (size_t j = 1; j < particles.size(); ++j) {
            if ((vertices.positions[i] - particles.positions[j]).lengthSqr()
                < (vertices.positions[i] - particles.positions[nearest]).lengthSqr()) {
                nearest = j;
            }
        }
        ASSERT_LT((vertices.positions[i] - particles.positions[nearest]).length(), 0.3f) << "vertex " << i;
        ASSERT_EQ(index->asDouble(i), particles.findAttribute("index")->asDouble(nearest)) << "vertex " << i;
        nearestOf[i] = nearest;
    }

    // Ids past 2^32 (a float32 holds every integer only to 2^24) come through exact: PLY
    // double, VTK vtktypeint64, without a word.
    ParticleSet big = particles;
    ParticleAttribute id;
    id.name = "id";
    id.type = nonbloppy::ScalarType::Int64;
    const int64_t firstId = (int64_t(1) << 40) + 1;
    for (size_t j = 0; j < big.size(); ++j) {
        const int64_t value = firstId + int64_t(j);
        const auto* bytes = reinterpret_cast<const unsigned char*>(&value);
        id.bytes.insert(id.bytes.end(), bytes, bytes + sizeof(value));
    }
    big.attributes = {id};
    nonbloppy::writeParticles(big, path("big.vtu"));  // PLY has no 64-bit integers
    for (const std::string out : {"b.ply", "b.vtk"}) {
        const RunResult exact = run("mesh -q " + quote(path("big.vtu")) + " -o " + quote(path(out)) +
                                    " --radius 0.3 --attributes id");
        ASSERT_EQ(exact.exitCode, 0) << exact.err;
        EXPECT_EQ(exact.err, "");
        const ParticleSet back = nonbloppy::readParticles(path(out));
        ASSERT_EQ(back.size(), vertices.size()) << out;
        const ParticleAttribute* ids = back.findAttribute("id");
        ASSERT_NE(ids, nullptr) << out;
        EXPECT_EQ(ids->type, out == "b.ply" ? nonbloppy::ScalarType::Float64 : nonbloppy::ScalarType::Int64);
        for (size_t i = 0; i < back.size(); ++i) {
            ASSERT_EQ(int64_t(ids->asDouble(i)), firstId + int64_t(nearestOf[i])) << out << " vertex " << i;
        }
    }

    // Past 2^53 a double rounds them: PLY (no 64-bit integers) says so, VTK keeps them.
    const int64_t pastDouble = (int64_t(1) << 53) + 1;
    for (size_t j = 0; j < big.size(); ++j) {
        const int64_t value = pastDouble + int64_t(j);
        std::memcpy(big.attributes[0].bytes.data() + 8 * j, &value, 8);
    }
    nonbloppy::writeParticles(big, path("past.vtu"));
    const std::string warning = "nonbloppy: warning: attribute 'id' holds integers past 2^53, which " + path("p.ply") +
                                " stores as doubles, rounded (PLY has no 64-bit integers); write .vtk to keep them exact\n";
    const RunResult rounded = run("mesh -q " + quote(path("past.vtu")) + " -o " + quote(path("p.ply")) +
                                  " --radius 0.3 --attributes id");
    EXPECT_EQ(rounded.exitCode, 0);
    EXPECT_EQ(rounded.err, warning);
    const RunResult converted = run("convert -q " + quote(path("past.vtu")) + " " + quote(path("p.ply")));
    EXPECT_EQ(converted.exitCode, 0);
    EXPECT_EQ(converted.err, warning);
    // A .vdb keeps int64 scalars, but its integer vectors are 32-bit: an int64 3-vector is a
    // vec3d, which rounded 2^53 + 1 without a word (bug hunt); --vdb-points likewise.
    ParticleSet vectors = big;
    vectors.attributes[0].name = "cell";
    vectors.attributes[0].components = 3;
    vectors.positions.resize(big.size() / 3);
    vectors.attributes[0].bytes.resize(vectors.positions.size() * 3 * 8);
    nonbloppy::writeParticles(vectors, path("cells.vtu"));
    EXPECT_EQ(run("convert -q " + quote(path("past.vtu")) + " " + quote(path("ids.vdb"))).err, "");
    EXPECT_EQ(run("convert -q " + quote(path("cells.vtu")) + " " + quote(path("cells.vdb"))).err,
              "nonbloppy: warning: attribute 'cell' holds integers past 2^53, which " + path("cells.vdb")
                  + " stores as doubles, rounded (OpenVDB has no 64-bit integer vectors); write .vtk to keep them "
                    "exact\n");
    const RunResult points = run("mesh -q " + quote(path("cells.vtu")) + " -o " + quote(path("c.vtk"))
                                 + " --radius 0.3 --vdb " + quote(path("c.vdb")) + " --vdb-points");
    EXPECT_EQ(points.exitCode, 0);
    EXPECT_EQ(points.err, "nonbloppy: warning: attribute 'cell' holds integers past 2^53, which " + path("c.vdb")
                              + " stores as doubles, rounded (OpenVDB has no 64-bit integer vectors); write .vtk to "
                                "keep them exact\n");
    EXPECT_EQ(nonbloppy::readParticles(path("ids.vdb")).findAttribute("id")->type, nonbloppy::ScalarType::Int64);

    const RunResult exact = run("mesh -q " + quote(path("past.vtu")) + " -o " + quote(path("p.vtk")) +
                                " --radius 0.3 --attributes id");
    EXPECT_EQ(exact.exitCode, 0);
    EXPECT_EQ(exact.err, "");
    const ParticleSet back = nonbloppy::readParticles(path("p.vtk"));
    const ParticleAttribute* ids = back.findAttribute("id");
    ASSERT_NE(ids, nullptr);
    ASSERT_EQ(ids->type, nonbloppy::ScalarType::Int64);
    for (size_t i = 0; i < back.size(); ++i) {
        int64_t value;
        std::memcpy(&value, ids->bytes.data() + 8 * i, 8);
        ASSERT_EQ(value, pastDouble + int64_t(nearestOf[i])) << "vertex " << i;
    }

    // A uint64 past int64 has no place in a mesh attribute: refused once the frame is read,
    // before it is meshed (-v lists the stages that ran), naming the file.
    big.attributes[0].type = nonbloppy::ScalarType::UInt64;
    const uint64_t tooLarge = std::numeric_limits<uint64_t>::max();
    std::memcpy(big.attributes[0].bytes.data() + 8 * 5, &tooLarge, 8);
    nonbloppy::writeParticles(big, path("hash.vtu"));
    const RunResult refused = run("mesh -v " + quote(path("hash.vtu")) + " -o " + quote(path("h.vtk")) +
                                  " --radius 0.3 --attributes id");
    EXPECT_EQ(refused.exitCode, 1);
    EXPECT_EQ(lines(refused.err).back(), "nonbloppy: " + path("hash.vtu") + ": attribute 'id' holds 18446744073709551615, "
                                         "above 9223372036854775807, the largest integer a mesh attribute holds");
    EXPECT_EQ(refused.err.find("rasterize density"), std::string::npos) << refused.err;
    EXPECT_FALSE(fs::exists(path("h.vtk")));
}

TEST_F(CliFormatsTest, AMeshGivenAsParticlesIsSaidToBeOne)
{
    // A mesh from an earlier run given back as IN: its vertices are meshed, with a warning.
    const std::string cube = kData + "/cube_2366_particles.vtk";
    ASSERT_EQ(run("mesh -q " + quote(cube) + " -o " + quote(path("surface.ply"))).exitCode, 0);
    const RunResult again = run("mesh -q " + quote(path("surface.ply")) + " -o " + quote(path("again.ply")));
    EXPECT_EQ(again.exitCode, 0) << again.err;
    EXPECT_EQ(again.err, "nonbloppy: warning: " + path("surface.ply") + " is a mesh (its element 'face' was not "
                         "read): its vertices were meshed as particles\n");
    // A legacy VTK mesh alike (it was meshed without a word: bug hunt), and convert says so.
    ASSERT_EQ(run("mesh -q " + quote(cube) + " -o " + quote(path("surface.vtk"))).exitCode, 0);
    const RunResult vtk = run("mesh -q " + quote(path("surface.vtk")) + " -o " + quote(path("again2.ply")));
    EXPECT_EQ(vtk.exitCode, 0) << vtk.err;
    EXPECT_EQ(vtk.err, "nonbloppy: warning: " + path("surface.vtk") + " is a mesh (its POLYGONS section was not "
                       "read): its vertices were meshed as particles\n");
    // Said once, also where the attributes are used (the faces were "not read" as well).
    const RunResult points = run("mesh -q " + quote(path("surface.ply")) + " -o " + quote(path("again3.ply")) +
                                 " --vdb " + quote(path("again3.vdb")) + " --vdb-points");
    EXPECT_EQ(points.err, again.err);
    const RunResult converted = run("convert -q " + quote(path("surface.ply")) + " " + quote(path("v.csv")));
    EXPECT_EQ(converted.exitCode, 0) << converted.err;
    EXPECT_EQ(converted.err, "nonbloppy: warning: not read from " + path("surface.ply") + ", so not converted: "
                             "element 'face'\n");
    // A PLY of particles: nothing to say.
    ASSERT_EQ(run("convert -q " + quote(cube) + " " + quote(path("particles.ply"))).exitCode, 0);
    const RunResult particles = run("mesh -q " + quote(path("particles.ply")) + " -o " + quote(path("p.ply")));
    EXPECT_EQ(particles.exitCode, 0);
    EXPECT_EQ(particles.err, "");
}

TEST_F(CliFormatsTest, VdbSurfaceAndPointsGrids)
{
    openvdb::initialize();
    const std::string source = kData + "/fluid_250_particles.vtu";
    const std::string vdb = path("all.vdb"), ply = path("m.ply");
    const RunResult r = run("mesh " + quote(source) + " -o " + quote(ply) + " --vdb " + quote(vdb) +
                            " --vdb-surface --vdb-points");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    // The grids' making is timed on its own; it was part of "write vdb" (bug hunt).
    EXPECT_NE(r.out.find("\n  build vdb grids "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\n  write vdb "), std::string::npos) << r.out;
    openvdb::io::File file(vdb);
    file.open();
    openvdb::GridPtrVecPtr grids = file.getGrids();
    file.close();
    ASSERT_EQ(grids->size(), 3u);
    std::map<std::string, openvdb::GridBase::Ptr> byName;
    for (const auto& grid : *grids) byName[grid->getName()] = grid;
    ASSERT_EQ(byName.size(), 3u);
    ASSERT_TRUE(byName.count("density") && byName.count("surface") && byName.count("points"));
    EXPECT_EQ(byName["surface"]->getGridClass(), openvdb::GRID_LEVEL_SET);
    const auto points = openvdb::gridPtrCast<openvdb::points::PointDataGrid>(byName["points"]);
    ASSERT_TRUE(points);
    EXPECT_EQ(openvdb::points::pointCount(points->tree()), 250u);
    EXPECT_EQ(nonbloppy::readParticles(vdb).attributes.size(), 4u);

    // The level set is ~0 at the mesh's vertices.
    const auto surface = openvdb::gridPtrCast<openvdb::FloatGrid>(byName["surface"]);
    const double h = surface->voxelSize()[0];
    const nonbloppy::SurfaceMesh mesh = nonbloppy::readMesh(ply);
    ASSERT_GT(mesh.points.size(), 100u);
    openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(*surface);
    for (size_t i = 0; i < mesh.points.size(); i += 7) {
        ASSERT_LT(std::abs(sampler.wsSample(openvdb::Vec3d(mesh.points[i]))), 1.0 * h) << "vertex " << i;
    }

    // Same bytes with one thread.
    const RunResult one = run("mesh -q --threads 1 " + quote(source) + " -o " + quote(path("one.ply")) +
                              " --vdb " + quote(path("one.vdb")) + " --vdb-surface --vdb-points --attributes all");
    ASSERT_EQ(one.exitCode, 0) << one.err;
    const RunResult many = run("mesh -q " + quote(source) + " -o " + quote(path("many.ply")) +
                               " --vdb " + quote(path("many.vdb")) + " --vdb-surface --vdb-points --attributes all");
    ASSERT_EQ(many.exitCode, 0) << many.err;
    EXPECT_TRUE(readText(path("one.vdb")) == readText(path("many.vdb")));
    EXPECT_TRUE(readText(path("one.ply")) == readText(path("many.ply")));

    const RunResult needsVdb = run("mesh " + quote(source) + " -o " + quote(path("x.ply")) + " --vdb-surface");
    EXPECT_EQ(needsVdb.exitCode, 2);
    EXPECT_EQ(needsVdb.err, "nonbloppy: --vdb-surface requires --vdb\n");
}

} // namespace

TEST_F(CliFormatsTest, FullDiskWhileWritingVdbIsAnErrorAndLeavesNothing)
{
    // A file-size limit (32 blocks: 16 KB in dash, 32 KB in bash; the mesh is 8 KB, the grids
    // 23 and 90 KB) stands in for a full disk: writes past it fail (EFBIG), as nonbloppy
    // ignores SIGXFSZ itself (here at its default action, which ended the run with exit 153
    // and left the temporary file). io::File never checked its stream: the .vdb came out
    // truncated, exit 0.
    const std::string outDir = path("out");
    const auto runLimited = [&](const std::string& args) {
        const std::string command = "ulimit -f 32; exec " + quote(kCli) + " " + args + " >"
                                    + quote(path("stdout.txt")) + " 2>" + quote(path("stderr.txt")) + " </dev/null";
        const int status = std::system(command.c_str());
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    };
    const std::string vdb = outDir + "/fluid.vdb";
    EXPECT_EQ(runLimited("convert " + quote(kData + "/fluid_250_particles.vtu") + " " + quote(vdb)), 1);
    EXPECT_EQ(readText(path("stderr.txt")), "nonbloppy: cannot write " + vdb + ": File too large\n");
    EXPECT_TRUE(listDir(outDir).empty()) << "output files left behind";

    const std::string grids = outDir + "/cube.vdb";
    EXPECT_EQ(runLimited("mesh " + quote(kData + "/cube_8_particles.vtk") + " -q -o " + quote(outDir + "/cube.ply")
                         + " --vdb " + quote(grids) + " --vdb-points --vdb-surface"), 1);
    EXPECT_EQ(readText(path("stderr.txt")), "nonbloppy: cannot write " + grids + ": File too large\n");
    EXPECT_TRUE(listDir(outDir).empty()) << "output files left behind";
}

TEST_F(CliFormatsTest, RenamedAttributesStayDistinctAndReadBack)
{
    // "a b" becomes a_b beside an a_b; an attribute x meets the positions; "my attr" cannot
    // be an OpenVDB name. Before, the CSV had two a_b columns, which nonbloppy itself then
    // refused ("duplicate column"), and .vdb failed with OpenVDB's "invalid characters".
    ParticleSet particles;
    particles.positions = {{0.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}};
    const auto add = [&](const std::string& name, int components, float first) {
        std::vector<float> values;
        for (int k = 0; k < 2 * components; ++k) values.push_back(first + float(k));
        particles.attributes.push_back(ParticleAttribute::of(name, components, values));
    };
    add("a b", 1, 10.0f);
    add("a_b", 1, 20.0f);
    add("x", 1, 50.0f);
    add("my attr", 1, 60.0f);
    // The CSV reader takes X and P:0..2 for positions too ("two columns for coordinate x"
    // on nonbloppy's own file); .vdb dropped an attribute P without a word.
    add("X", 1, 70.0f);
    add("P", 3, 80.0f);
    // The name each attribute reads back under, per format; an unchanged name keeps its own.
    const std::map<std::string, std::vector<std::string>> expected{
        {".csv", {"a_b_2", "a_b", "x_2", "my_attr", "X_2", "P_2"}},
        {".ply", {"a_b_2", "a_b", "x_2", "my_attr", "X", "P"}},
        {".vtk", {"a_b_2", "a_b", "x_2", "my_attr", "X", "P_2"}},
        {".vtu", {"a_b_2", "a_b", "x_2", "my_attr", "X", "P_2"}},
        {".vdb", {"a_b_2", "a_b", "x_2", "my_attr", "X", "P_2"}}};
    for (const auto& [ext, names] : expected) {
        const std::string file = path("renamed" + ext);
        // What the writer tells a caller beforehand is what it writes.
        EXPECT_EQ(nonbloppy::writtenAttributeNames(particles, file), names) << ext;
        nonbloppy::writeParticles(particles, file);
        const ParticleSet back = nonbloppy::readParticles(file);
        ASSERT_EQ(back.size(), particles.size()) << ext;
        for (size_t i = 0; i < names.size(); ++i) {
            const ParticleAttribute* a = back.findAttribute(names[i]);
            ASSERT_NE(a, nullptr) << ext << " " << names[i];
            EXPECT_EQ(a->components, particles.attributes[i].components) << ext << " " << names[i];
            for (size_t n = 0; n < back.size(); ++n) {
                // Match by position: a .vdb may reorder the particles.
                const size_t original = back.positions[n][0] > 0.5f ? 1 : 0;
                EXPECT_EQ(a->asDouble(n, 0), particles.attributes[i].asDouble(original, 0)) << ext << " " << names[i];
            }
        }
    }
}

TEST_F(CliFormatsTest, RenamedAttributesAreNamedInAWarning)
{
    // .xyz drops attributes (named by its own warning); an unknown extension is the writer's
    // error. Then the command line: attributes renamed for the output format got no word.
    ParticleSet two;
    two.positions = {{0.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}};
    two.attributes.push_back(ParticleAttribute::of("a b", 1, std::vector<float>{0.0f, 0.0f}));
    EXPECT_EQ(nonbloppy::writtenAttributeNames(two, path("p.xyz")), std::vector<std::string>{""});
    try {
        nonbloppy::writtenAttributeNames(two, path("p.obj"));
        ADD_FAILURE() << "no exception";
    } catch (const nonbloppy::FileError& e) {
        EXPECT_EQ(std::string(e.what()), "unknown particle output extension '.obj' (" + path("p.obj")
                                             + "); expected .ply, .vtk, .vtu, .xyz, .csv or .vdb");
    }

    // A 6x6x6 block (spacing 0.05) with attributes "a b", a_b and nx.
    std::string csv = "x,y,z,a b,a_b,nx\n";
    for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j)
            for (int k = 0; k < 6; ++k)
                csv += std::to_string(0.05 * i) + "," + std::to_string(0.05 * j) + "," + std::to_string(0.05 * k)
                       + "," + std::to_string(i) + "," + std::to_string(j) + "," + std::to_string(k) + "\n";
    const std::string source = path("named.csv");
    writeText(source, csv);

    RunResult r = run("convert -q " + quote(source) + " " + quote(path("c.ply")));
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_EQ(r.err, "nonbloppy: warning: attribute 'a b' is written to " + path("c.ply") + " as 'a_b_2'\n");
    r = run("convert -q " + quote(source) + " " + quote(path("c.vtu")));
    EXPECT_EQ(r.err, "nonbloppy: warning: attribute 'a b' is written to " + path("c.vtu") + " as 'a_b_2'\n");

    // On a mesh, nx also meets the normals' property (before: two properties "nx").
    r = run("mesh -q " + quote(source) + " -o " + quote(path("m.ply")) + " --attributes all");
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_EQ(r.err, "nonbloppy: warning: attribute 'a b' is written to " + path("m.ply") + " as 'a_b_2'\n"
                     "nonbloppy: warning: attribute 'nx' is written to " + path("m.ply") + " as 'nx_2'\n");
    const std::string header = readText(path("m.ply")).substr(0, 400);
    // (Whole numbers in every row: the CSV reader makes them integers, carried as ints.)
    EXPECT_NE(header.find("property float nz\nproperty int a_b_2\nproperty int a_b\nproperty int nx_2\n"
                          "element face"), std::string::npos) << header;
    // Only the renamed ones are named; OBJ keeps its own warning.
    r = run("mesh -q " + quote(source) + " -o " + quote(path("m2.ply")) + " --attributes a_b");
    EXPECT_EQ(r.err, "");
    r = run("mesh -q " + quote(source) + " -o " + quote(path("m.obj")) + " --attributes all");
    EXPECT_EQ(r.err, "nonbloppy: warning: OBJ cannot store vertex attributes; write .ply or .vtk to keep "
                     "--attributes\n");
}

TEST_F(CliFormatsTest, InspectOfAPointsVdbCountsItsPointsAndNamesItsAttributes)
{
    // It showed voxels and leaves only; and convert's creator named no version.
    const std::string vdb = path("f.vdb");
    ASSERT_EQ(run("convert -q " + quote(kData + "/fluid_250_particles.vtu") + " " + quote(vdb)).exitCode, 0);
    const RunResult text = run("inspect " + quote(vdb));
    ASSERT_EQ(text.exitCode, 0) << text.err;
    EXPECT_NE(text.out.find("  creator: " + nonbloppy::versionLine() + "\n"), std::string::npos)
        << text.out;
    // mesh's .vdb says it alike: as --version prints it, OpenVDB's version included (docs/farm.md).
    ASSERT_EQ(run("mesh -q " + quote(kData + "/fluid_250_particles.vtu") + " -o " + quote(path("m.ply")) + " --vdb "
                  + quote(path("m.vdb"))).exitCode, 0);
    EXPECT_NE(run("inspect " + quote(path("m.vdb"))).out.find("  creator: " + nonbloppy::versionLine()
                                                              + "\n"),
              std::string::npos);
    EXPECT_NE(text.out.find("\n    points: 250; attributes: P vec3s, velocity vec3d, pressure double, density double, "
                            "index int64\n"),
              std::string::npos)
        << text.out;
    const RunResult json = run("inspect --json " + quote(vdb));
    ASSERT_EQ(json.exitCode, 0) << json.err;
    EXPECT_NE(json.out.find("\"points\": 250,"), std::string::npos) << json.out;
    EXPECT_NE(json.out.find("\"name\": \"velocity\",\n          \"type\": \"vec3d\""), std::string::npos) << json.out;
}

TEST_F(CliFormatsTest, WideIntegersSurviveAVdbOrAreRefused)
{
    // 3-vectors of uint32 and int64 were stored as vec3i: 4e9 and 2^40 read back as
    // -2147483648. A uint64 above 2^63 - 1 read back as -9.22e18.
    ParticleSet particles;
    particles.positions = {{0.0f, 0.0f, 0.0f}};
    particles.attributes.push_back(ParticleAttribute::of("u", 3, std::vector<uint32_t>{4000000000u, 1u, 2u}));
    particles.attributes.push_back(ParticleAttribute::of("i", 3, std::vector<int64_t>{int64_t(1) << 40, -5, 7}));
    // Scalars above 2^53 keep every bit (they went through a double: 2^62 + 1 became 2^62).
    const int64_t id = (int64_t(1) << 62) + 1;
    const uint64_t largest = uint64_t(std::numeric_limits<int64_t>::max());
    particles.attributes.push_back(ParticleAttribute::of("id", 1, std::vector<int64_t>{id}));
    particles.attributes.push_back(ParticleAttribute::of("largest", 1, std::vector<uint64_t>{largest}));
    const std::string file = path("wide.vdb");
    nonbloppy::writeParticles(particles, file);
    const ParticleSet back = nonbloppy::readParticles(file);
    for (const auto& [name, values] : {std::pair<const char*, std::vector<double>>{"u", {4e9, 1, 2}},
                                       {"i", {1099511627776.0, -5, 7}}}) {
        const ParticleAttribute* a = back.findAttribute(name);
        ASSERT_NE(a, nullptr) << name;
        ASSERT_EQ(a->components, 3) << name;
        for (int c = 0; c < 3; ++c) EXPECT_EQ(a->asDouble(0, c), values[size_t(c)]) << name << c;
    }
    for (const auto& [name, expected] : {std::pair<const char*, int64_t>{"id", id}, {"largest", int64_t(largest)}}) {
        const ParticleAttribute* a = back.findAttribute(name);
        ASSERT_NE(a, nullptr) << name;
        ASSERT_EQ(a->type, nonbloppy::ScalarType::Int64) << name;
        int64_t value = 0;
        std::memcpy(&value, a->bytes.data(), sizeof(value));
        EXPECT_EQ(value, expected) << name;
    }
    particles.attributes.push_back(ParticleAttribute::of("h", 1, std::vector<uint64_t>{std::numeric_limits<uint64_t>::max()}));
    std::string message;
    try {
        nonbloppy::writeParticles(particles, path("huge.vdb"));
    } catch (const nonbloppy::ParameterError& e) {
        message = e.what();
    }
    // Named as the other refusals of writeParticles() are (it named no file).
    EXPECT_EQ(message, "attribute 'h' holds 18446744073709551615, above 9223372036854775807, the largest integer "
                       "a .vdb stores (" + path("huge.vdb") + ")");
    EXPECT_FALSE(std::filesystem::exists(path("huge.vdb")));
}

TEST_F(CliFormatsTest, PlyKeeps64BitIntegersAsIntegersWhereTheyFit32Bits)
{
    // PLY has no 64-bit type. They went out as double, so ids read back as floats (and were
    // averaged by mesh --attributes); now as int or uint where every value fits.
    ParticleSet particles;
    particles.positions = {{0.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}};
    particles.attributes.push_back(ParticleAttribute::of("id", 1, std::vector<int64_t>{-2147483648LL, 2147483647LL}));
    particles.attributes.push_back(ParticleAttribute::of("big", 1, std::vector<int64_t>{0, int64_t(1) << 40}));
    particles.attributes.push_back(ParticleAttribute::of("count", 1, std::vector<uint64_t>{0, 4294967295ULL}));
    nonbloppy::writeParticles(particles, path("p.ply"));
    const std::string header = readText(path("p.ply")).substr(0, 200);
    EXPECT_NE(header.find("property int id\nproperty double big\nproperty uint count\n"), std::string::npos) << header;
    const ParticleSet back = nonbloppy::readParticles(path("p.ply"));
    const std::vector<std::tuple<const char*, nonbloppy::ScalarType, double, double>> expected{
        {"id", nonbloppy::ScalarType::Int32, -2147483648.0, 2147483647.0},
        {"big", nonbloppy::ScalarType::Float64, 0.0, 1099511627776.0},
        {"count", nonbloppy::ScalarType::UInt32, 0.0, 4294967295.0}};
    for (const auto& [name, type, first, second] : expected) {
        const ParticleAttribute* a = back.findAttribute(name);
        ASSERT_NE(a, nullptr) << name;
        EXPECT_EQ(a->type, type) << name;
        EXPECT_EQ(a->asDouble(0), first) << name;
        EXPECT_EQ(a->asDouble(1), second) << name;
    }
}

TEST_F(CliFormatsTest, AVdbCannotHoldANonFinitePositionAndSaysSo)
{
    // OpenVDB's partitioning dropped such a particle without a word; the other formats
    // write it as it is, so a round trip through .vdb lost particles.
    nonbloppy::ParticleSet particles;
    particles.positions = {{0, 0, 0}, {0.1f, 0, 0}, {0, std::numeric_limits<float>::quiet_NaN(), 0}, {0, 0, 0.1f}};
    const std::string file = path("nan.vdb");
    std::string message;
    try {
        nonbloppy::writeParticles(particles, file);
    } catch (const nonbloppy::ParameterError& e) {
        message = e.what();
    }
    EXPECT_EQ(message, "non-finite position of particle 2, which a .vdb points grid cannot hold (" + file + ")");
    EXPECT_FALSE(std::filesystem::exists(file));
    particles.positions[2][1] = std::numeric_limits<float>::infinity();
    try {
        nonbloppy::makePointDataGrid(particles);
        message.clear();
    } catch (const nonbloppy::ParameterError& e) {
        message = e.what();
    }
    EXPECT_EQ(message, "non-finite position of particle 2, which a .vdb points grid cannot hold");
    // The other formats write it as it is (readParticles() then names it).
    nonbloppy::writeParticles(particles, path("inf.ply"));
    EXPECT_EQ(nonbloppy_test::messageOf<nonbloppy::ParameterError>([&] { nonbloppy::readParticles(path("inf.ply")); }),
              "non-finite position of particle 2 (" + path("inf.ply") + ")");
}

TEST_F(CliFormatsTest, WhatIsNotReadIsSaid)
{
    // A .vdb's group converted to nothing, and inspect did not show it.
    const std::vector<openvdb::Vec3R> positions{{0.0, 0.0, 0.0}, {1.0, 2.0, 3.0}};
    const std::string vdb = path("grouped.vdb");
    nonbloppy_test::writeOpenVdbPoints(vdb, positions, 0.5, nonbloppy_test::PointExtras::IdPairAndGroup);
    const RunResult converted = run("convert -q " + quote(vdb) + " " + quote(path("g.csv")));
    EXPECT_EQ(converted.exitCode, 0);
    EXPECT_EQ(converted.err, "nonbloppy: warning: not read from " + vdb + ", so not converted: group 'tagged'\n");
    // inspect of particles lists it (a .vdb is inspected as grids, its group among them).
    writeText(path("listed.ply"), "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                  "property float z\nproperty list uchar int ids\nend_header\n1 2 3 2 7 8\n");
    const RunResult inspected = run("inspect " + quote(path("listed.ply")));
    EXPECT_NE(inspected.out.find("\n  not read         list property 'ids'\n"), std::string::npos) << inspected.out;
    const nlohmann::json report = nlohmann::json::parse(run("inspect --json " + quote(path("listed.ply"))).out);
    EXPECT_EQ(report.at("not_read"), nlohmann::json::array({"list property 'ids'"}));
    EXPECT_EQ(nlohmann::json::parse(run("inspect --json " + quote(path("g.csv"))).out).at("not_read"),
              nlohmann::json::array());
    // mesh says so where it uses the attributes, once.
    const RunResult meshed = run("mesh -q " + quote(vdb) + " -o " + quote(path("m.ply")) + " --radius 2 --voxel-size 0.5 "
                                 "--threshold 0.5 --attributes id");
    EXPECT_EQ(meshed.exitCode, 0) << meshed.err;
    EXPECT_EQ(meshed.err, "nonbloppy: warning: not read from " + vdb + ": group 'tagged'\n");
    EXPECT_EQ(run("mesh -q " + quote(vdb) + " -o " + quote(path("m.ply")) + " --radius 2 --voxel-size 0.5 "
                  "--threshold 0.5").err, "");
}

TEST_F(CliFormatsTest, ParticlesFarFromTheOriginAreWarnedOfTheirFloatStep)
{
    // The cube of particles moved 1e5 out: float positions there step by 1/128, more than
    // 1/16 of the spacing 0.05, and the surface came out quantized without a word.
    nonbloppy::ParticleSet particles = nonbloppy::readParticles(kData + "/cube_2366_particles.vtk");
    for (openvdb::Vec3f& p : particles.positions) p[0] += 1.0e5f;
    const std::string far = path("far.ply"), mesh = path("far_mesh.ply");
    nonbloppy::writeParticles(particles, far);
    const RunResult r = run("mesh " + quote(far) + " -q -o " + quote(mesh) + " --spacing 0.05");
    EXPECT_EQ(r.exitCode, 0) << r.err;
    float farthest = 0.0f;
    for (const openvdb::Vec3f& p : particles.positions) {
        for (int k = 0; k < 3; ++k) farthest = std::max(farthest, std::abs(p[k]));
    }
    ASSERT_GT(farthest, 1.0e5f);
    std::ostringstream shown;  // as the tool prints numbers: %g, 6 significant digits
    shown << double(farthest);
    EXPECT_EQ(r.err, "nonbloppy: warning: the particles reach " + shown.str() +
                         " from the origin, where float positions step by 0.0078125, more than 1/16 of the "
                         "spacing 0.05: the surface is quantized there; move the particles nearer the origin\n");

    // A droplet of 27 particles 4e6 out, where floats step by 0.25, became one point and left
    // no vertex: the warning looked at the mesh, so the loss went unsaid.
    nonbloppy::ParticleSet scene = nonbloppy::readParticles(kData + "/cube_2366_particles.vtk");
    for (int i = 0; i < 27; ++i) {
        scene.positions.emplace_back(4.0e6f + 0.05f * float(i % 3), 0.05f * float(i / 3 % 3), 0.05f * float(i / 9));
    }
    nonbloppy::writeParticles(scene, path("droplet.ply"));
    const RunResult lost = run("mesh " + quote(path("droplet.ply")) + " -q -o " + quote(mesh) + " --spacing 0.05");
    EXPECT_EQ(lost.exitCode, 0) << lost.err;
    EXPECT_EQ(lost.err, "nonbloppy: warning: the particles reach 4e+06 from the origin, where float positions step "
                        "by 0.25, more than 1/16 of the spacing 0.05: the surface is quantized there, and droplets "
                        "may vanish; move the particles nearer the origin\n");
    // At the origin, no warning.
    EXPECT_EQ(run("mesh " + quote(kData + "/cube_2366_particles.vtk") + " -q -o " + quote(mesh) + " --spacing 0.05").err,
              "");

    // Particles in one plane, whose bounding box OpenVDB calls empty, went unwarned; so did
    // any run without a spacing (r_e, r_0 and h given), now measured against h/8 (bug hunt).
    nonbloppy::ParticleSet sheet;
    for (int i = 0; i < 400; ++i) sheet.positions.emplace_back(1.0e5f + 0.05f * float(i % 20), 0.05f * float(i / 20), 1.0e5f);
    nonbloppy::writeParticles(sheet, path("sheet.ply"));
    const RunResult flat = run("mesh " + quote(path("sheet.ply")) + " -q -o " + quote(mesh) + " --spacing 0.05");
    EXPECT_EQ(flat.exitCode, 0) << flat.err;
    EXPECT_EQ(flat.err, "nonbloppy: warning: the particles reach 100001 from the origin, where float positions step by "
                        "0.0078125, more than 1/16 of the spacing 0.05: the surface is quantized there; move the "
                        "particles nearer the origin\n");
    const RunResult noSpacing = run("mesh " + quote(far) + " -q -o " + quote(mesh) +
                                    " --radius 0.1 --voxel-size 0.025 --threshold 3");
    EXPECT_EQ(noSpacing.exitCode, 0) << noSpacing.err;
    EXPECT_EQ(noSpacing.err, "nonbloppy: warning: the particles reach " + shown.str() +
                                 " from the origin, where float positions step by 0.0078125, more than 1/8 of the "
                                 "voxel size 0.025: the surface is quantized there; move the particles nearer the "
                                 "origin\n");
}

TEST_F(CliFormatsTest, AttributesOfTheWrongShapeAreNamedAndNothingIsWritten)
{
    nonbloppy::ParticleSet particles;
    particles.positions = {{0, 0, 0}, {0.1f, 0, 0}};
    nonbloppy::ParticleAttribute attribute;
    attribute.name = "speed";
    attribute.type = nonbloppy::ScalarType::Float32;
    attribute.components = 0;  // was reported as "does not hold one value per particle"
    attribute.bytes.resize(8);
    particles.attributes.push_back(attribute);
    const std::string file = path("shape.ply");
    const auto message = [&] {
        return nonbloppy_test::messageOf<nonbloppy::ParameterError>([&] { nonbloppy::writeParticles(particles, file); });
    };
    EXPECT_EQ(message(), "attribute 'speed' has 0 components, at least 1 needed (" + file + ")");
    particles.attributes[0].components = 1;
    particles.attributes[0].bytes.resize(4);  // one float for two particles
    EXPECT_EQ(message(), "attribute 'speed' does not hold one value per particle (" + file + ")");
    EXPECT_FALSE(std::filesystem::exists(file));
    // The in-memory grid refuses it too (it used to leave the attribute out silently).
    EXPECT_EQ(nonbloppy_test::messageOf<nonbloppy::ParameterError>([&] { nonbloppy::makePointDataGrid(particles); }),
              "attribute 'speed' does not hold one value per particle");
}

TEST_F(CliFormatsTest, APointsGridRefusesVoxelSizesThatWouldLoseThePositions)
{
    // 0.001 put the particles at +1e9 and -3e7 both in voxel -2^31; NaN picked a size silently.
    ParticleSet particles;
    particles.positions = {{0.0f, 0.0f, 0.0f}, {1e9f, 0.0f, 0.0f}, {-3e7f, 2.0f, 5.0f}};
    EXPECT_EQ(nonbloppy_test::messageOf<nonbloppy::ParameterError>([&] { nonbloppy::makePointDataGrid(particles, 0.001); }),
              "particle coordinates up to 1e+09 are too far from the origin for a voxel size of 0.001 (32-bit index space)");
    EXPECT_EQ(nonbloppy_test::messageOf<nonbloppy::ParameterError>([&] { nonbloppy::makePointDataGrid(particles, std::nan("")); }),
              "--voxel-size must be finite, got nan");
    EXPECT_EQ(nonbloppy_test::messageOf<nonbloppy::ParameterError>([&] {
                  nonbloppy::makePointDataGrid(particles, -std::numeric_limits<double>::infinity());
              }), "--voxel-size must be finite, got -inf");
    const auto grid = openvdb::gridPtrCast<openvdb::points::PointDataGrid>(nonbloppy::makePointDataGrid(particles, 10.0));
    ASSERT_TRUE(grid);
    EXPECT_EQ(openvdb::points::pointCount(grid->tree()), 3u);
}

TEST_F(CliFormatsTest, AnEmptyParticleFileKeepsItsAttributesThroughAVdb)
{
    // Zero particles through .vdb lost their attributes without a word (format round-trip
    // hunt): OpenVDB made no leaf, and only leaves describe attributes.
    const std::string csv = path("empty.csv"), vdb = path("empty.vdb");
    writeText(csv, "x,y,z,temperature,v:0,v:1,v:2\n");
    RunResult r = run("convert " + quote(csv) + " " + quote(vdb));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err, "");
    EXPECT_EQ(r.out, "converted 0 particles with 2 attributes: " + csv + " -> " + vdb + "\n");
    r = run("convert -q " + quote(vdb) + " " + quote(path("back.csv")));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err, "");
    EXPECT_EQ(readText(path("back.csv")), "x,y,z,temperature,v:0,v:1,v:2\n");
    r = run("inspect " + quote(vdb));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("\n    points: 0; attributes: P vec3s, temperature int64, v vec3d\n"), std::string::npos) << r.out;
}
