// SPDX-License-Identifier: Apache-2.0
// Tests for readParticles(): the real SPlisHSPlasH frames in tests/data, synthetic VTK, PLY
// and XYZ files written here, and truncated or corrupt input.

#include "TestUtil.h"
#include "support/AllocationRecorder.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/ReadParticles.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

using nonbloppy_test::dataPath;
using nonbloppy_test::messageOf;
using nonbloppy_test::readBytes;
using nonbloppy_test::writeBytes;

using nonbloppy::FileError;
using nonbloppy::ParameterError;
using nonbloppy::ParticleSet;
using nonbloppy::ScalarType;
using nonbloppy::readParticles;

class ReadParticlesTest : public nonbloppy_test::ScratchDirTest
{
};


std::string
fileErrorOf(const std::string& path)
{
    return messageOf<FileError>([&] { readParticles(path); });
}

// Big-endian and little-endian byte helpers for writing binary test files.
template<typename T>
std::string
bigEndian(T value)
{
    std::string bytes(sizeof(T), '\0');
    std::memcpy(bytes.data(), &value, sizeof(T));
    std::reverse(bytes.begin(), bytes.end());  // test machines are little-endian
    return bytes;
}

template<typename T>
std::string
littleEndian(T value)
{
    std::string bytes(sizeof(T), '\0');
    std::memcpy(bytes.data(), &value, sizeof(T));
    return bytes;
}

// ------------------------------------------------------------------------------------------
// Real files

struct RealFile
{
    const char* name;
    size_t count;
    bool hasIdAndVelocity;
};

const RealFile kRealFiles[] = {
    {"dam_break_frame_23_24389_particles.vtk", 24389, true},
    {"double_dam_break_frame_26_4732_particles.vtk", 4732, true},
    {"bunny_frame_14_7705_particles.vtk", 7706, true},
    {"cube_2366_particles.vtk", 2366, false},
    {"cube_8_particles.vtk", 8, false},
    {"free_particles_125_particles.vtk", 125, false},
};

TEST(ReadParticles, RealVtkFilesHaveTheDocumentedCountsAndAttributes)
{
    for (const RealFile& file : kRealFiles) {
        SCOPED_TRACE(file.name);
        const ParticleSet particles = readParticles(dataPath(file.name));
        ASSERT_EQ(particles.size(), file.count);

        openvdb::Vec3f lo(std::numeric_limits<float>::max());
        openvdb::Vec3f hi(-std::numeric_limits<float>::max());
        for (const openvdb::Vec3f& p : particles.positions) {
            ASSERT_TRUE(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]));
            lo = openvdb::math::minComponent(lo, p);
            hi = openvdb::math::maxComponent(hi, p);
        }
        // Every scene is a few metres across (spacing 0.05) except the scattered
        // free particles (spacing 0.8, about 10 units wide).
        const openvdb::Vec3f extent = hi - lo;
        for (int axis = 0; axis < 3; ++axis) {
            EXPECT_GT(extent[axis], 0.0f);
            EXPECT_LT(extent[axis], 12.0f);
        }

        if (!file.hasIdAndVelocity) {
            EXPECT_TRUE(particles.attributes.empty());
            continue;
        }
        ASSERT_EQ(particles.attributes.size(), 2u);
        const nonbloppy::ParticleAttribute* id = particles.findAttribute("id");
        const nonbloppy::ParticleAttribute* velocity = particles.findAttribute("velocity");
        ASSERT_NE(id, nullptr);
        ASSERT_NE(velocity, nullptr);
        EXPECT_EQ(particles.findAttribute("pressure"), nullptr);

        EXPECT_EQ(id->type, ScalarType::UInt32);
        EXPECT_EQ(id->components, 1);
        ASSERT_EQ(id->size(), file.count);
        // SPlisHSPlasH ids are a permutation of 0..n-1.
        std::vector<bool> seen(file.count, false);
        for (size_t i = 0; i < file.count; ++i) {
            const double value = id->asDouble(i);
            ASSERT_GE(value, 0.0);
            ASSERT_LT(value, double(file.count));
            ASSERT_FALSE(seen[size_t(value)]) << "duplicate id " << value;
            seen[size_t(value)] = true;
        }

        EXPECT_EQ(velocity->type, ScalarType::Float32);
        EXPECT_EQ(velocity->components, 3);
        ASSERT_EQ(velocity->size(), file.count);
        double maxSpeedComponent = 0.0;
        for (size_t i = 0; i < file.count; ++i) {
            for (int c = 0; c < 3; ++c) {
                const double v = velocity->asDouble(i, c);
                ASSERT_TRUE(std::isfinite(v));
                maxSpeedComponent = std::max(maxSpeedComponent, std::abs(v));
            }
        }
        EXPECT_GT(maxSpeedComponent, 0.1);   // the fluid moves
        EXPECT_LT(maxSpeedComponent, 20.0);  // a few m/s, not garbage
    }
}

TEST(ParticleAttribute, OfTypesTheValuesAfterTheirCppTypeAndKeepsTheirBytes)
{
    using nonbloppy::ParticleAttribute;
    using nonbloppy::scalarTypeOf;
    static_assert(scalarTypeOf<int8_t>() == ScalarType::Int8 && scalarTypeOf<uint8_t>() == ScalarType::UInt8);
    static_assert(scalarTypeOf<int16_t>() == ScalarType::Int16 && scalarTypeOf<uint16_t>() == ScalarType::UInt16);
    static_assert(scalarTypeOf<int32_t>() == ScalarType::Int32 && scalarTypeOf<uint32_t>() == ScalarType::UInt32);
    static_assert(scalarTypeOf<int64_t>() == ScalarType::Int64 && scalarTypeOf<uint64_t>() == ScalarType::UInt64);
    static_assert(scalarTypeOf<float>() == ScalarType::Float32 && scalarTypeOf<double>() == ScalarType::Float64);

    const ParticleAttribute velocity = ParticleAttribute::of("velocity", 3, std::vector<double>{1, 2, 3, 4, 5, 6.5});
    EXPECT_EQ(velocity.name, "velocity");
    EXPECT_EQ(velocity.type, ScalarType::Float64);
    EXPECT_EQ(velocity.components, 3);
    EXPECT_EQ(velocity.size(), 2u);
    EXPECT_EQ(velocity.asDouble(1, 2), 6.5);
    const ParticleAttribute id = ParticleAttribute::of("id", 1, std::vector<uint64_t>{~uint64_t(0)});
    EXPECT_EQ(id.bytes, std::vector<unsigned char>(8, 0xff));
    EXPECT_TRUE(ParticleAttribute::of("none", 1, std::vector<int16_t>{}).bytes.empty());
}

TEST(ReadParticles, Cube8HasItsExactAsciiCoordinates)
{
    const ParticleSet particles = readParticles(dataPath("cube_8_particles.vtk"));
    const float expected[8][3] = {
        {0.5f, 0.4995095f, 0.5f}, {0.5f, 0.4995095f, 1.0f},
        {0.5f, 0.9995095f, 0.5f}, {0.5f, 0.9995095f, 1.0f},
        {1.0f, 0.4995095f, 0.5f}, {1.0f, 0.4995095f, 1.0f},
        {1.0f, 0.9995095f, 0.5f}, {1.0f, 0.9995095f, 1.0f},
    };
    ASSERT_EQ(particles.size(), 8u);
    for (size_t i = 0; i < 8; ++i) {
        for (int axis = 0; axis < 3; ++axis) {
            EXPECT_EQ(particles.positions[i][axis], expected[i][axis]) << i << " " << axis;
        }
    }
    EXPECT_TRUE(particles.attributes.empty());
}

TEST(ReadParticles, Cube2366IsARegularBlock)
{
    // 13 × 14 × 13 particles at spacing 0.05.
    const ParticleSet particles = readParticles(dataPath("cube_2366_particles.vtk"));
    openvdb::Vec3f lo(1e30f), hi(-1e30f);
    for (const openvdb::Vec3f& p : particles.positions) {
        lo = openvdb::math::minComponent(lo, p);
        hi = openvdb::math::maxComponent(hi, p);
    }
    EXPECT_NEAR(lo[0], 0.85, 1e-5);
    EXPECT_NEAR(lo[1], 0.05, 1e-4);
    EXPECT_NEAR(hi[0], 1.45, 1e-5);
    EXPECT_NEAR(hi[1], 0.70, 1e-4);
    EXPECT_NEAR(hi[2], 1.45, 1e-5);
}

TEST(ReadParticles, BinaryVtkPositionsAreDecodedBigEndian)
{
    // Decode the first and last particles of the dam break independently of the reader.
    const std::string path = dataPath("dam_break_frame_23_24389_particles.vtk");
    const std::string bytes = readBytes(path);
    const std::string header = "POINTS 24389 float\n";
    const size_t start = bytes.find(header) + header.size();
    auto coordinate = [&](size_t index) {
        uint32_t bits = 0;
        for (int b = 0; b < 4; ++b) bits = (bits << 8) | uint8_t(bytes[start + 4 * index + b]);
        float value;
        std::memcpy(&value, &bits, 4);
        return value;
    };
    const ParticleSet particles = readParticles(path);
    for (size_t n : {size_t(0), size_t(1), size_t(24388)}) {
        for (int axis = 0; axis < 3; ++axis) {
            EXPECT_EQ(particles.positions[n][axis], coordinate(3 * n + size_t(axis)));
        }
    }
}

TEST_F(ReadParticlesTest, ExtensionIsCaseInsensitive)
{
    writeBytes(path("upper.VTK"), readBytes(dataPath("cube_8_particles.vtk")));
    EXPECT_EQ(readParticles(path("upper.VTK")).size(), 8u);
    EXPECT_TRUE(nonbloppy::isParticleFile("a/b.Ply"));
    EXPECT_TRUE(nonbloppy::isParticleFile("x.xyz"));
    EXPECT_TRUE(nonbloppy::isParticleFile("x.VTU"));
    EXPECT_FALSE(nonbloppy::isParticleFile("x.vtm"));
    EXPECT_FALSE(nonbloppy::isParticleFile("dir.vtk/file"));
    EXPECT_FALSE(nonbloppy::isParticleFile("vtk"));
}

// ------------------------------------------------------------------------------------------
// Synthetic VTK

TEST_F(ReadParticlesTest, AsciiPolydataWithEveryArrayKind)
{
    const std::string text =
        "# vtk DataFile Version 5.1\n"
        "synthetic\n"
        "ASCII\n"
        "DATASET POLYDATA\n"
        "FIELD FieldData 1\n"
        "TIME 1 1 double\n"
        "0.25\n"
        "POINTS 3 float\n"
        "0 1 2  3.5 -4 5e-1\n"
        "+6 7 8\n"
        "METADATA\n"
        "INFORMATION 0\n"
        "\n"
        "VERTICES 4 3\n"
        "OFFSETS vtktypeint64\n"
        "0 1 2 3\n"
        "CONNECTIVITY vtktypeint64\n"
        "0 1 2\n"
        "POINT_DATA 3\n"
        "SCALARS density double\n"
        "LOOKUP_TABLE default\n"
        "1000.5 999 1001\n"
        "SCALARS flags unsigned_char 2\n"   // VTK 5 may omit LOOKUP_TABLE
        "1 2 3 4 5 255\n"
        "VECTORS velocity float\n"
        "1 0 0 0 1 0 0 0 1\n"
        "METADATA\n"
        "INFORMATION 1\n"
        "NAME L2_NORM_RANGE LOCATION vtkDataArray\n"
        "DATA 2 1 1\n"
        "\n"
        "FIELD FieldData 2\n"
        "id 1 3 long\n"
        "-7 8 9000000000\n"
        "my%20mass 1 3 short\n"
        "-1 2 3\n"
        "CELL_DATA 3\n"
        "SCALARS cellValue int 1\n"
        "LOOKUP_TABLE default\n"
        "1 2 3\n";
    writeBytes(path("synthetic.vtk"), text);
    const ParticleSet particles = readParticles(path("synthetic.vtk"));
    ASSERT_EQ(particles.size(), 3u);
    EXPECT_EQ(particles.positions[0], openvdb::Vec3f(0, 1, 2));
    EXPECT_EQ(particles.positions[1], openvdb::Vec3f(3.5f, -4, 0.5f));
    EXPECT_EQ(particles.positions[2], openvdb::Vec3f(6, 7, 8));

    ASSERT_EQ(particles.attributes.size(), 5u);  // cell data and dataset FIELD are dropped
    const auto* density = particles.findAttribute("density");
    ASSERT_NE(density, nullptr);
    EXPECT_EQ(density->type, ScalarType::Float64);
    EXPECT_EQ(density->asDouble(0), 1000.5);
    EXPECT_EQ(density->asDouble(2), 1001.0);

    const auto* flags = particles.findAttribute("flags");
    ASSERT_NE(flags, nullptr);
    EXPECT_EQ(flags->type, ScalarType::UInt8);
    EXPECT_EQ(flags->components, 2);
    EXPECT_EQ(flags->asDouble(2, 1), 255.0);

    const auto* velocity = particles.findAttribute("velocity");
    ASSERT_NE(velocity, nullptr);
    EXPECT_EQ(velocity->components, 3);
    EXPECT_EQ(velocity->asDouble(1, 1), 1.0);
    EXPECT_EQ(velocity->asDouble(1, 0), 0.0);

    const auto* id = particles.findAttribute("id");
    ASSERT_NE(id, nullptr);
    EXPECT_EQ(id->type, ScalarType::Int64);
    EXPECT_EQ(id->asDouble(0), -7.0);
    EXPECT_EQ(id->asDouble(2), 9e9);

    const auto* mass = particles.findAttribute("my mass");  // %20 decoded
    ASSERT_NE(mass, nullptr);
    EXPECT_EQ(mass->type, ScalarType::Int16);
    EXPECT_EQ(mass->asDouble(0), -1.0);
}

/// A binary VTK 5.1 file with double points and 64-bit offsets, built byte by byte.
std::string
binaryVtk51()
{
    std::string bytes = "# vtk DataFile Version 5.1\nbinary test\nBINARY\nDATASET UNSTRUCTURED_GRID\n";
    bytes += "POINTS 2 double\n";
    for (double v : {1.0, 2.0, 3.0, -0.125, 1e-3, 4e6}) bytes += bigEndian(v);
    bytes += "\nCELLS 3 2\nOFFSETS vtktypeint64\n";
    for (int64_t v : {0, 1, 2}) bytes += bigEndian(v);
    bytes += "\nCONNECTIVITY vtktypeint64\n";
    for (int64_t v : {0, 1}) bytes += bigEndian(v);
    bytes += "\nCELL_TYPES 2\n";
    for (int32_t v : {1, 1}) bytes += bigEndian(v);
    bytes += "\nPOINT_DATA 2\nSCALARS temperature float 1\nLOOKUP_TABLE default\n";
    for (float v : {300.5f, -1.0f}) bytes += bigEndian(v);
    bytes += "\nFIELD FieldData 2\nindex 1 2 unsigned_short\n";
    for (uint16_t v : {65535, 7}) bytes += bigEndian(v);
    bytes += "\nMETADATA\nINFORMATION 0\n\nflag 1 2 char\n";
    bytes += std::string("\xff\x05", 2);
    bytes += "\n";
    return bytes;
}

TEST_F(ReadParticlesTest, BinaryVtk51WithDoublePointsAndOffsets)
{
    writeBytes(path("binary51.vtk"), binaryVtk51());
    const ParticleSet particles = readParticles(path("binary51.vtk"));
    ASSERT_EQ(particles.size(), 2u);
    EXPECT_EQ(particles.positions[0], openvdb::Vec3f(1, 2, 3));
    EXPECT_EQ(particles.positions[1], openvdb::Vec3f(-0.125f, float(1e-3), 4e6f));
    ASSERT_EQ(particles.attributes.size(), 3u);
    EXPECT_EQ(particles.attributes[0].name, "temperature");
    EXPECT_EQ(particles.attributes[0].asDouble(0), 300.5);
    EXPECT_EQ(particles.attributes[1].name, "index");
    EXPECT_EQ(particles.attributes[1].type, ScalarType::UInt16);
    EXPECT_EQ(particles.attributes[1].asDouble(0), 65535.0);
    EXPECT_EQ(particles.attributes[1].asDouble(1), 7.0);
    EXPECT_EQ(particles.attributes[2].name, "flag");
    EXPECT_EQ(particles.attributes[2].type, ScalarType::Int8);
    EXPECT_EQ(particles.attributes[2].asDouble(0), -1.0);
    EXPECT_EQ(particles.attributes[2].asDouble(1), 5.0);
}

TEST_F(ReadParticlesTest, ZeroParticlesIsNotAnErrorAtReadTime)
{
    writeBytes(path("empty.vtk"),
        "# vtk DataFile Version 4.1\nempty\nBINARY\nDATASET UNSTRUCTURED_GRID\n"
        "POINTS 0 float\n\nCELLS 0 0\n\nCELL_TYPES 0\n\nPOINT_DATA 0\n");
    EXPECT_EQ(readParticles(path("empty.vtk")).size(), 0u);
    writeBytes(path("empty.xyz"), "");
    EXPECT_EQ(readParticles(path("empty.xyz")).size(), 0u);
}

// ------------------------------------------------------------------------------------------
// PLY and XYZ

struct PlyVertex
{
    float x, y, z;
    uint8_t red;
    int32_t id;
    double pressure;
};

const std::vector<PlyVertex> kPlyVertices = {
    {0.0f, 1.0f, 2.0f, 0, -5, 1.5},
    {0.1f, -0.2f, 1e-7f, 255, 2147483647, -1e300},
    {123456.78f, 3.25f, -0.0f, 17, 0, 0.0},
};

/// A PLY file in @a format whose vertex element also has a list property (skipped), and
/// which has a face element before and after it (both skipped).
std::string
makePly(const std::string& format)
{
    std::ostringstream os;
    os << "ply\nformat " << format << " 1.0\ncomment test\n"
       << "element material 1\nproperty uchar shininess\n"
       << "element vertex " << kPlyVertices.size() << "\n"
       << "property float x\nproperty float y\nproperty uchar red\n"
       << "property list uchar int neighbours\n"
       << "property float z\nproperty int id\nproperty double pressure\n"
       << "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    std::string bytes = os.str();
    const bool ascii = format == "ascii";
    const bool big = format == "binary_big_endian";
    auto put = [&](auto value) {
        if (ascii) {
            std::ostringstream text;
            text.precision(17);
            text << +value << ' ';
            bytes += text.str();
        } else {
            bytes += big ? bigEndian(value) : littleEndian(value);
        }
    };
    put(uint8_t(9));  // material
    if (ascii) bytes += "\n";
    for (const PlyVertex& v : kPlyVertices) {
        put(v.x); put(v.y); put(v.red);
        put(uint8_t(2)); put(int32_t(1)); put(int32_t(2));  // neighbours list
        put(v.z); put(v.id); put(v.pressure);
        if (ascii) bytes += "\n";
    }
    put(uint8_t(3)); put(int32_t(0)); put(int32_t(1)); put(int32_t(2));
    if (ascii) bytes += "\n";
    return bytes;
}

TEST_F(ReadParticlesTest, PlyInAllThreeEncodingsReadsBackExactly)
{
    for (const std::string format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
        SCOPED_TRACE(format);
        writeBytes(path("p.ply"), makePly(format));
        const ParticleSet particles = readParticles(path("p.ply"));
        ASSERT_EQ(particles.size(), kPlyVertices.size());
        ASSERT_EQ(particles.attributes.size(), 3u);
        EXPECT_EQ(particles.attributes[0].name, "red");
        EXPECT_EQ(particles.attributes[0].type, ScalarType::UInt8);
        EXPECT_EQ(particles.attributes[1].name, "id");
        EXPECT_EQ(particles.attributes[1].type, ScalarType::Int32);
        EXPECT_EQ(particles.attributes[2].name, "pressure");
        EXPECT_EQ(particles.attributes[2].type, ScalarType::Float64);
        for (size_t i = 0; i < kPlyVertices.size(); ++i) {
            const PlyVertex& v = kPlyVertices[i];
            EXPECT_EQ(particles.positions[i], openvdb::Vec3f(v.x, v.y, v.z));
            EXPECT_EQ(particles.attributes[0].asDouble(i), double(v.red));
            EXPECT_EQ(particles.attributes[1].asDouble(i), double(v.id));
            EXPECT_EQ(particles.attributes[2].asDouble(i), v.pressure);
        }
    }
}

TEST_F(ReadParticlesTest, PlyWithDoubleCoordinates)
{
    std::string bytes = "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
        "property double x\nproperty double y\nproperty double z\nend_header\n";
    for (double v : {0.5, -2.0, 1e10}) bytes += littleEndian(v);
    writeBytes(path("d.ply"), bytes);
    const ParticleSet particles = readParticles(path("d.ply"));
    ASSERT_EQ(particles.size(), 1u);
    EXPECT_EQ(particles.positions[0], openvdb::Vec3f(0.5f, -2.0f, 1e10f));
    EXPECT_TRUE(particles.attributes.empty());
}

TEST_F(ReadParticlesTest, XyzReadsBackExactly)
{
    const std::vector<float> values = {0, 1, 2, -3.5f, 1e-30f, 7e30f, 0.1f, 0.2f, 0.3f};
    std::string bytes;
    for (float v : values) bytes += littleEndian(v);
    writeBytes(path("p.xyz"), bytes);
    const ParticleSet particles = readParticles(path("p.xyz"));
    ASSERT_EQ(particles.size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
        EXPECT_EQ(particles.positions[i],
            openvdb::Vec3f(values[3 * i], values[3 * i + 1], values[3 * i + 2]));
    }
    EXPECT_TRUE(particles.attributes.empty());

    writeBytes(path("odd.xyz"), bytes.substr(0, 13));
    EXPECT_EQ(fileErrorOf(path("odd.xyz")), "XYZ file size 13 is not a multiple of 12 bytes "
        "(three float32 per particle) (" + path("odd.xyz") + ")");
}

// ------------------------------------------------------------------------------------------
// Errors

TEST_F(ReadParticlesTest, MissingFileAndUnknownExtension)
{
    EXPECT_EQ(fileErrorOf(path("missing.vtk")),
        "cannot open " + path("missing.vtk") + ": No such file or directory");
    EXPECT_EQ(fileErrorOf(path("particles.foo")),
        "unknown particle file extension '.foo' (" + path("particles.foo") +
        "); expected .vtk, .vtu, .vtp, .ply, .xyz, .bgeo, .vdb, .csv, .txt or .json");
    EXPECT_EQ(fileErrorOf(path("particles")),
        "particle file name has no extension (" + path("particles") +
        "); expected .vtk, .vtu, .vtp, .ply, .xyz, .bgeo, .vdb, .csv, .txt or .json");
    const std::string directory = path("dir.vtk");
    ASSERT_EQ(mkdir(directory.c_str(), 0755), 0);
    EXPECT_EQ(fileErrorOf(directory), "cannot read " + directory + ": Is a directory");

    // requireParticleFile() refuses the same names with the same words, by the name alone
    // (none of these files exists), and lets every name readParticles() takes through.
    for (const std::string name : {"particles.foo", "particles", "cache.bgeo.sc", "cache.geo"}) {
        SCOPED_TRACE(name);
        std::string message;
        try {
            nonbloppy::requireParticleFile(path(name));
        } catch (const FileError& e) {
            message = e.what();
        }
        EXPECT_EQ(message, fileErrorOf(path(name)));
        EXPECT_FALSE(message.empty());
    }
    for (const std::string name : {"a.vtk", "a.VTU", "a.vtp", "a.ply", "a.xyz", "a.bgeo", "a.bgeo.gz", "a.bhclassic",
                                   "a.bhclassic.gz", "a.vdb", "a.csv", "a.txt", "a.json"}) {
        EXPECT_NO_THROW(nonbloppy::requireParticleFile(path(name))) << name;
    }
}

TEST_F(ReadParticlesTest, TruncatedRealFilesNameTheSection)
{
    const std::string original = readBytes(dataPath("dam_break_frame_23_24389_particles.vtk"));
    const std::string p = path("cut.vtk");
    auto cutAt = [&](size_t k) {
        writeBytes(p, original.substr(0, k));
        return fileErrorOf(p);
    };
    auto offsetAfter = [&](const std::string& header) {
        return original.find(header) + header.size();
    };
    EXPECT_EQ(cutAt(offsetAfter("POINTS 24389 float\n") + 1000),
        "truncated POINTS section (" + p + ")");
    EXPECT_EQ(cutAt(offsetAfter("CELLS 24389 48778\n") + 7),
        "truncated CELLS section (" + p + ")");
    EXPECT_EQ(cutAt(offsetAfter("CELL_TYPES 24389\n") + 4 * 24388),
        "truncated CELL_TYPES section (" + p + ")");
    EXPECT_EQ(cutAt(offsetAfter("LOOKUP_TABLE id_table\n") + 3),
        "truncated SCALARS 'id' section (" + p + ")");
    EXPECT_EQ(cutAt(original.size() - 2), "truncated FIELD array 'velocity' (" + p + ")");
    EXPECT_EQ(cutAt(offsetAfter("DATASET UNSTRUCTURED_GRID\n")),
        "missing POINTS section in VTK file (" + p + ")");
    EXPECT_EQ(cutAt(offsetAfter("BINARY\n")), "truncated VTK header (" + p + ")");
    EXPECT_EQ(cutAt(0), "not a legacy VTK file: the first line must start with "
        "'# vtk DataFile' (" + p + ")");
    EXPECT_EQ(cutAt(offsetAfter("POINTS 24389")),
        "bad header 'POINTS 24389' in VTK file (" + p + ")");
}

TEST_F(ReadParticlesTest, EveryPrefixOfARealFileFailsCleanlyOrReadsTheWholeBlock)
{
    // A cut exactly between two sections can leave a valid, shorter file; any other cut
    // must be reported as a FileError naming the file, never a crash or a hang.
    for (const char* name : {"free_particles_125_particles.vtk", "cube_8_particles.vtk"}) {
        const std::string original = readBytes(dataPath(name));
        const size_t count = readParticles(dataPath(name)).size();
        const std::string p = path(std::string("prefix_") + name);
        // Every length for the small file; every 7th (still ~450 cuts) for the larger one.
        const size_t stride = original.size() > 1000 ? 7 : 1;
        size_t failures = 0, cuts = 0;
        for (size_t k = 0; k < original.size(); k += stride, ++cuts) {
            writeBytes(p, original.substr(0, k));
            try {
                const ParticleSet particles = readParticles(p);
                EXPECT_EQ(particles.size(), count) << name << " cut at " << k;
            } catch (const FileError& e) {
                const std::string message = e.what();
                ASSERT_NE(message.find("(" + p + ")"), std::string::npos) << message;
                ASSERT_EQ(message.find('\n'), std::string::npos) << message;
                ++failures;
            }
        }
        EXPECT_GT(failures, cuts / 2) << name;
    }
}

TEST_F(ReadParticlesTest, HeadersClaimingMoreThanTheFileHoldsAreRejectedBeforeAllocating)
{
    const std::string p = path("huge.vtk");
    writeBytes(p, "# vtk DataFile Version 4.1\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\n"
        "POINTS 1000000000 float\n" + std::string(36, '\0'));
    EXPECT_EQ(fileErrorOf(p), "truncated POINTS section (" + p + ")");

    writeBytes(p, "# vtk DataFile Version 4.1\nx\nASCII\nDATASET POLYDATA\n"
        "POINTS 18446744073709551615 double\n0 0 0\n");
    EXPECT_EQ(fileErrorOf(p), "truncated POINTS section (" + p + ")");

    writeBytes(p, "# vtk DataFile Version 4.1\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\n"
        "POINTS 1 float\n" + std::string(12, '\0') +
        "\nPOINT_DATA 1\nFIELD FieldData 1\nv 3000000000 1 double\n" + std::string(24, '\0'));
    EXPECT_EQ(fileErrorOf(p), "bad header 'v 3000000000 1 double' in VTK file (" + p + ")");

    const std::string ply = path("huge.ply");
    writeBytes(ply, "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n"
        "property float x\nproperty float y\nproperty float z\nend_header\n" +
        std::string(24, '\0'));
    std::string message;
    EXPECT_LT(nonbloppy_test::largestAllocationDuring([&] { message = fileErrorOf(ply); }), size_t(2) << 20);
    EXPECT_EQ(message, "truncated PLY vertex element (" + ply + ")");
    EXPECT_LT(nonbloppy_test::largestAllocationDuring([&] { message = fileErrorOf(p); }), size_t(2) << 20);
}

// A file that really holds more particles than the machine's memory (here sparse files, which
// take no disk) is refused by name before its arrays are allocated, not with std::bad_alloc
// ("out of memory", naming nothing) or by the kernel's OOM killer.
TEST_F(ReadParticlesTest, FilesHoldingMoreParticlesThanMemoryAreRefusedBeforeAllocating)
{
    const long pages = sysconf(_SC_PHYS_PAGES), pageSize = sysconf(_SC_PAGE_SIZE);
    ASSERT_GT(pages, 0);
    ASSERT_GT(pageSize, 0);
    // Twice the machine's memory in float32 positions alone.
    const uint64_t count = 2 * uint64_t(pages) * uint64_t(pageSize) / 12;
    const std::string countText = std::to_string(count);
    const auto sparseFile = [&](const std::string& file, const std::string& header, uint64_t dataBytes) {
        writeBytes(file, header);
        if (truncate(file.c_str(), off_t(header.size() + dataBytes)) != 0) return false;
        return true;
    };
    const std::string ply = path("many.ply"), xyz = path("many.xyz"), vtk = path("many.vtk");
    if (!sparseFile(ply, "ply\nformat binary_little_endian 1.0\nelement vertex " + countText +
                             "\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
                    count * 12)) {
        GTEST_SKIP() << "this file system holds no sparse file of " << count * 12 << " bytes";
    }
    ASSERT_TRUE(sparseFile(xyz, "", count * 12));
    ASSERT_TRUE(sparseFile(vtk, "# vtk DataFile Version 4.1\nx\nBINARY\nDATASET POLYDATA\nPOINTS " + countText +
                                    " float\n", count * 12));
    for (const std::string& file : {ply, xyz, vtk}) {
        std::string message;
        EXPECT_LT(nonbloppy_test::largestAllocationDuring([&] { message = fileErrorOf(file); }), size_t(2) << 20)
            << file;
        const std::string start = countText + " particles would take ";
        const std::string end = " this process can still take (" + file + ")";
        EXPECT_EQ(message.substr(0, start.size()), start) << message;
        EXPECT_NE(message.find(" of memory, more than the "), std::string::npos) << message;
        ASSERT_GE(message.size(), end.size()) << message;
        EXPECT_EQ(message.substr(message.size() - end.size()), end) << message;
    }
}

TEST_F(ReadParticlesTest, CorruptHeadersGiveOneLineMessages)
{
    const std::string p = path("bad.vtk");
    const std::string start = "# vtk DataFile Version 4.1\nx\nASCII\n";
    struct Case { std::string body; std::string message; };
    const std::vector<Case> cases = {
        {"DATASET STRUCTURED_POINTS\n",
         "unsupported VTK dataset 'STRUCTURED_POINTS'; expected UNSTRUCTURED_GRID or POLYDATA"},
        {"POINTS 1 float\n", "expected 'DATASET <type>' in VTK file, got 'POINTS 1 float'"},
        {"DATASET POLYDATA\nPOINTS 1 int\n1 2 3\n",
         "unsupported POINTS type 'int'; expected float or double"},
        {"DATASET POLYDATA\nPOINTS 1 float\n1 2 x\n", "bad float32 value 'x' in POINTS section"},
        {"DATASET POLYDATA\nPOINTS 1 float\n1 2 3\nPOINT_DATA 2\n",
         "POINT_DATA count 2 differs from POINTS count 1"},
        {"DATASET POLYDATA\nPOINT_DATA 2\nSCALARS a float\n1 2\nPOINTS 1 float\n1 2 3\n",
         "POINT_DATA count 2 differs from POINTS count 1"},
        {"DATASET POLYDATA\nPOINTS 1 float\n1 2 3\nSCALARS a float\n1\n",
         "SCALARS before POINT_DATA or CELL_DATA in VTK file"},
        {"DATASET POLYDATA\nPOINTS 1 float\n1 2 3\nPOINT_DATA 1\nSCALARS a bit\n1\n",
         "unsupported VTK data type 'bit'"},
        {"DATASET POLYDATA\nPOINTS 1 float\n1 2 3\nBOGUS 1\n", "unexpected 'BOGUS' in VTK file"},
        {"DATASET POLYDATA\nPOINTS 1 float\n1 2 3\nPOINTS 1 float\n1 2 3\n",
         "second POINTS section in VTK file"},
    };
    for (const Case& c : cases) {
        writeBytes(p, start + c.body);
        EXPECT_EQ(fileErrorOf(p), c.message + " (" + p + ")");
    }
    writeBytes(p, "# vtk DataFile Version 4.1\nx\nTEXT\n");
    EXPECT_EQ(fileErrorOf(p), "bad VTK file type 'TEXT'; expected ASCII or BINARY (" + p + ")");

    const std::string ply = path("bad.ply");
    writeBytes(ply, "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
        "property float x\nproperty float y\nend_header\n");
    EXPECT_EQ(fileErrorOf(ply), "PLY vertex element has no 'z' property (" + ply + ")");
    writeBytes(ply, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
    EXPECT_EQ(fileErrorOf(ply), "truncated PLY header: no end_header line (" + ply + ")");
    writeBytes(ply, "ply\nformat ascii 1.0\nelement vertex 1\nproperty quaternion q\nend_header\n");
    EXPECT_EQ(fileErrorOf(ply), "bad PLY header line 'property quaternion q' (" + ply + ")");
    writeBytes(ply, "solid\n");
    EXPECT_EQ(fileErrorOf(ply), "not a PLY file: the first line must be 'ply' (" + ply + ")");
}

TEST_F(ReadParticlesTest, NonFinitePositionsAreParameterErrors)
{
    std::string text = "# vtk DataFile Version 4.1\nx\nASCII\nDATASET POLYDATA\nPOINTS 20 float\n";
    for (int i = 0; i < 20; ++i) text += (i == 17) ? "0 nan 0\n" : "0 0 0\n";
    writeBytes(path("nan.vtk"), text);
    EXPECT_EQ(messageOf<ParameterError>([&] { readParticles(path("nan.vtk")); }),
        "non-finite position of particle 17 (" + path("nan.vtk") + ")");

    std::string bytes;
    for (float v : {0.0f, 0.0f, 0.0f, 1.0f, std::numeric_limits<float>::infinity(), 0.0f}) {
        bytes += littleEndian(v);
    }
    writeBytes(path("inf.xyz"), bytes);
    EXPECT_EQ(messageOf<ParameterError>([&] { readParticles(path("inf.xyz")); }),
        "non-finite position of particle 1 (" + path("inf.xyz") + ")");

    // A double that overflows float is as unusable as an infinity.
    std::string big = "# vtk DataFile Version 4.1\nx\nASCII\nDATASET POLYDATA\nPOINTS 1 double\n"
        "1e300 0 0\n";
    writeBytes(path("big.vtk"), big);
    EXPECT_EQ(messageOf<ParameterError>([&] { readParticles(path("big.vtk")); }),
        "non-finite position of particle 0 (" + path("big.vtk") + ")");
}

TEST_F(ReadParticlesTest, RandomCorruptionNeverCrashes)
{
    // Flip bytes of small valid files; each result must read or throw nonbloppy::Error.
    const std::vector<std::pair<std::string, std::string>> seeds = {
        {"a.vtk", readBytes(dataPath("cube_8_particles.vtk"))},
        {"b.vtk", readBytes(dataPath("free_particles_125_particles.vtk"))},
        {"c.vtk", binaryVtk51()},
        {"d.ply", makePly("ascii")},
        {"e.ply", makePly("binary_big_endian")},
    };
    std::mt19937 random(12345);
    size_t errors = 0, reads = 0;
    for (const auto& [name, original] : seeds) {
        for (int trial = 0; trial < 150; ++trial) {
            std::string bytes = original;
            const int flips = 1 + int(random() % 4);
            for (int f = 0; f < flips; ++f) {
                const size_t at = random() % bytes.size();
                const char choices[] = {'\0', '\n', ' ', '9', '-', 'x', char(0xff), char(random())};
                bytes[at] = choices[random() % sizeof(choices)];
            }
            writeBytes(path(name), bytes);
            try {
                readParticles(path(name));
                ++reads;
            } catch (const nonbloppy::Error& e) {
                EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
                ++errors;
            }
        }
    }
    EXPECT_GT(errors, 0u);
    EXPECT_GT(reads, 0u);
}

} // namespace
