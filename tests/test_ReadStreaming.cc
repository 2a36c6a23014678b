// SPDX-License-Identifier: Apache-2.0
// Tests for the streaming paths of readParticles() (legacy VTK, PLY, XYZ): files larger
// than the reader's 1 MiB chunk buffer, so values, records, text tokens and lines straddle
// chunk boundaries; every PLY layout (packed float x y z, interleaved attributes, double
// coordinates, list properties, elements before the vertices) in both byte orders and as
// text; VTK float and double points, attributes, and VTK 5 cell arrays that are skipped;
// truncation deep inside a file; and input from a pipe, which has no size.

#include "TestUtil.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/ReadParticles.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace {

using nonbloppy::FileError;
using nonbloppy::ParticleSet;
using nonbloppy::ScalarType;
using nonbloppy::readParticles;

using nonbloppy_test::writeBytes;

class ReadStreamingTest : public nonbloppy_test::ScratchDirTest
{
};

/// More particles than fit in the reader's 1 MiB buffer in any layout below
/// (12 bytes each for packed float x y z).
constexpr size_t kManyParticles = 150001;

/// The FileError message readParticles(@a path) throws ("" if none).
std::string
fileErrorOf(const std::string& path)
{
    return nonbloppy_test::messageOf<FileError>([&] { readParticles(path); });
}

template<typename T>
std::string
encode(T value, bool bigEndian)
{
    std::string bytes(sizeof(T), '\0');
    std::memcpy(bytes.data(), &value, sizeof(T));
    if (bigEndian) std::reverse(bytes.begin(), bytes.end());  // test machines are little-endian
    return bytes;
}

/// A text form of @a value that reads back exactly.
template<typename T>
std::string
text(T value)
{
    std::ostringstream os;
    os.precision(17);
    os << +value;
    return os.str();
}

/// Particle @a i of a synthetic frame: irregular values that differ in every byte.
struct Record
{
    float x, y, z;
    uint8_t red;
    int32_t id;
    double pressure;
};

Record
record(size_t i)
{
    const uint32_t h = uint32_t(i) * 2654435761u;
    return {float(i) * 0.001f - 7.5f, float(h % 100000u) * 0.01f, -float(i % 977) * 0.125f,
            uint8_t(h >> 24), int32_t(h - uint32_t(i)), double(i) * 1e-3 - 1e6};
}

/// Write @a bytes through a FIFO at @a path while @a read runs (pipes have no size).
template<typename F>
void
readThroughFifo(const std::string& path, const std::string& bytes, F&& read)
{
    ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
    std::signal(SIGPIPE, SIG_IGN);  // a reader that fails early must not kill the tests
    std::thread writer([&] {
        const int fd = ::open(path.c_str(), O_WRONLY);
        if (fd < 0) return;
        size_t done = 0;
        while (done < bytes.size()) {
            const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
            if (n <= 0) break;
            done += size_t(n);
        }
        ::close(fd);
    });
    read();
    writer.join();
}

// ------------------------------------------------------------------------------------------
// PLY

enum class Layout { PackedFloat, Interleaved, Double, WithList };

/// A PLY file of @a count records in @a format (ascii, binary_little_endian or
/// binary_big_endian). Interleaved: x red y id z pressure. WithList: as Interleaved plus a
/// list property in the vertex element and a 3000-record element before it.
std::string
makePly(const std::string& format, Layout layout, size_t count)
{
    std::string header = "ply\nformat " + format + " 1.0\ncomment streaming test\n";
    const bool ascii = format == "ascii";
    const bool big = format == "binary_big_endian";
    if (layout == Layout::WithList) {
        header += "element camera 3000\nproperty double focal\nproperty list uchar int tags\n";
    }
    header += "element vertex " + std::to_string(count) + "\n";
    switch (layout) {
        case Layout::PackedFloat:
            header += "property float x\nproperty float y\nproperty float z\n";
            break;
        case Layout::Interleaved:
        case Layout::WithList:
            header += "property float x\nproperty uchar red\nproperty float y\n"
                      "property int id\nproperty float z\nproperty double pressure\n";
            if (layout == Layout::WithList) header += "property list uchar int neighbours\n";
            break;
        case Layout::Double:
            header += "property double x\nproperty double y\nproperty double z\n";
            break;
    }
    header += "element face 1\nproperty list uchar int vertex_indices\nend_header\n";

    std::string body;
    body.reserve(count * 48);
    auto put = [&](auto value) {
        if (ascii) {
            body += text(value);
            body += ' ';
        } else {
            body += encode(value, big);
        }
    };
    if (layout == Layout::WithList) {
        for (int i = 0; i < 3000; ++i) {
            put(double(i) * 0.5);
            put(uint8_t(i % 4));
            for (int j = 0; j < i % 4; ++j) put(int32_t(j));
            if (ascii) body += '\n';
        }
    }
    for (size_t i = 0; i < count; ++i) {
        const Record r = record(i);
        switch (layout) {
            case Layout::PackedFloat: put(r.x); put(r.y); put(r.z); break;
            case Layout::Interleaved:
            case Layout::WithList:
                put(r.x); put(r.red); put(r.y); put(r.id); put(r.z); put(r.pressure);
                if (layout == Layout::WithList) {
                    put(uint8_t(i % 3));
                    for (size_t j = 0; j < i % 3; ++j) put(int32_t(i + j));
                }
                break;
            case Layout::Double:
                put(double(r.x) + 1e-9); put(double(r.y)); put(double(r.z) - 1e-9);
                break;
        }
        if (ascii) body += '\n';
    }
    put(uint8_t(3)); put(int32_t(0)); put(int32_t(1)); put(int32_t(2));
    if (ascii) body += '\n';
    return header + body;
}

void
expectRecords(const ParticleSet& particles, Layout layout, size_t count)
{
    ASSERT_EQ(particles.size(), count);
    const bool attributes = layout == Layout::Interleaved || layout == Layout::WithList;
    ASSERT_EQ(particles.attributes.size(), attributes ? 3u : 0u);
    if (attributes) {
        EXPECT_EQ(particles.attributes[0].name, "red");
        EXPECT_EQ(particles.attributes[0].type, ScalarType::UInt8);
        EXPECT_EQ(particles.attributes[1].name, "id");
        EXPECT_EQ(particles.attributes[1].type, ScalarType::Int32);
        EXPECT_EQ(particles.attributes[2].name, "pressure");
        EXPECT_EQ(particles.attributes[2].type, ScalarType::Float64);
        for (const auto& attribute : particles.attributes) EXPECT_EQ(attribute.size(), count);
    }
    size_t mismatches = 0;
    for (size_t i = 0; i < count && mismatches < 5; ++i) {
        const Record r = record(i);
        openvdb::Vec3f expected(r.x, r.y, r.z);
        if (layout == Layout::Double) {
            expected = openvdb::Vec3f(float(double(r.x) + 1e-9), r.y, float(double(r.z) - 1e-9));
        }
        bool same = particles.positions[i] == expected;
        if (attributes) {
            same = same && particles.attributes[0].asDouble(i) == double(r.red) &&
                particles.attributes[1].asDouble(i) == double(r.id) &&
                particles.attributes[2].asDouble(i) == r.pressure;
        }
        if (!same) {
            ++mismatches;
            ADD_FAILURE() << "particle " << i << ": " << particles.positions[i] << " expected "
                          << expected;
        }
    }
}

TEST_F(ReadStreamingTest, PlyLargerThanTheBufferInEveryLayoutAndEncoding)
{
    const std::pair<Layout, const char*> layouts[] = {
        {Layout::PackedFloat, "packed float"}, {Layout::Interleaved, "interleaved"},
        {Layout::Double, "double"}, {Layout::WithList, "with list"}};
    for (const auto& [layout, name] : layouts) {
        for (const std::string format : {"binary_little_endian", "binary_big_endian", "ascii"}) {
            SCOPED_TRACE(std::string(name) + ", " + format);
            const std::string bytes = makePly(format, layout, kManyParticles);
            ASSERT_GT(bytes.size(), size_t(1) << 20);
            writeBytes(path("big.ply"), bytes);
            expectRecords(readParticles(path("big.ply")), layout, kManyParticles);
        }
    }
}

TEST_F(ReadStreamingTest, PlyTruncatedInALaterChunkNamesTheElement)
{
    for (const std::string format : {"binary_little_endian", "ascii"}) {
        for (const Layout layout : {Layout::PackedFloat, Layout::Interleaved}) {
            SCOPED_TRACE(format);
            const std::string bytes = makePly(format, layout, kManyParticles);
            // Cut inside the last particles: the header's count no longer fits.
            const std::string p = path("cut.ply");
            writeBytes(p, bytes.substr(0, bytes.size() - 200));
            EXPECT_EQ(fileErrorOf(p), "truncated PLY vertex element (" + p + ")");
        }
    }
    // A bad text value far from the start is reported with its section.
    std::string bytes = makePly("ascii", Layout::PackedFloat, kManyParticles);
    const size_t at = bytes.find('\n', bytes.size() - 100000) + 1;
    bytes.replace(at, 1, "q");
    writeBytes(path("bad.ply"), bytes);
    const std::string message = fileErrorOf(path("bad.ply"));
    EXPECT_EQ(message.rfind("bad float32 value 'q", 0), 0u) << message;
    EXPECT_NE(message.find("' in PLY vertex element (" + path("bad.ply") + ")"),
              std::string::npos) << message;
}

TEST_F(ReadStreamingTest, PlyHeaderClaimingMoreThanTheFileIsRejected)
{
    for (const std::string format : {"binary_little_endian", "ascii"}) {
        const std::string p = path("huge.ply");
        writeBytes(p, "ply\nformat " + format + " 1.0\nelement vertex 1000000000\n"
            "property float x\nproperty float y\nproperty float z\nproperty uchar red\n"
            "end_header\n" + std::string(900, '1'));
        EXPECT_EQ(fileErrorOf(p), "truncated PLY vertex element (" + p + ")");
    }
}

TEST_F(ReadStreamingTest, PlyFromAPipe)
{
    const std::string bytes = makePly("binary_big_endian", Layout::WithList, kManyParticles);
    readThroughFifo(path("fifo.ply"), bytes, [&] {
        expectRecords(readParticles(path("fifo.ply")), Layout::WithList, kManyParticles);
    });
}

// ------------------------------------------------------------------------------------------
// Legacy VTK

/// A legacy VTK file with @a count points in @a type ("float" or "double"): VTK 5 cell
/// arrays (one vertex cell per point, skipped), a SCALARS array without LOOKUP_TABLE, a
/// VECTORS array and a FIELD array, all per point.
std::string
makeVtk(bool binary, const std::string& type, size_t count)
{
    std::string bytes = "# vtk DataFile Version 5.1\nstreaming test\n";
    bytes += binary ? "BINARY\n" : "ASCII\n";
    bytes += "DATASET UNSTRUCTURED_GRID\nPOINTS " + std::to_string(count) + " " + type + "\n";
    auto put = [&](auto value) {
        if (binary) {
            bytes += encode(value, /*bigEndian=*/true);
        } else {
            bytes += text(value);
            bytes += ' ';
        }
    };
    for (size_t i = 0; i < count; ++i) {
        const Record r = record(i);
        if (type == "double") {
            put(double(r.x)); put(double(r.y)); put(double(r.z));
        } else {
            put(r.x); put(r.y); put(r.z);
        }
        if (!binary) bytes += '\n';
    }
    bytes += "\nCELLS " + std::to_string(count + 1) + " " + std::to_string(count) +
        "\nOFFSETS vtktypeint64\n";
    for (size_t i = 0; i <= count; ++i) put(int64_t(i));
    bytes += "\nCONNECTIVITY vtktypeint64\n";
    for (size_t i = 0; i < count; ++i) put(int64_t(i));
    bytes += "\nCELL_TYPES " + std::to_string(count) + "\n";
    for (size_t i = 0; i < count; ++i) put(int32_t(1));
    bytes += "\nPOINT_DATA " + std::to_string(count) + "\nSCALARS id int\n";
    for (size_t i = 0; i < count; ++i) put(record(i).id);
    bytes += "\nVECTORS velocity float\n";
    for (size_t i = 0; i < count; ++i) {
        const Record r = record(i);
        put(r.z); put(r.x); put(r.y);
    }
    bytes += "\nFIELD FieldData 1\npressure 1 " + std::to_string(count) + " double\n";
    for (size_t i = 0; i < count; ++i) put(record(i).pressure);
    bytes += "\n";
    return bytes;
}

void
expectVtk(const ParticleSet& particles, size_t count)
{
    ASSERT_EQ(particles.size(), count);
    ASSERT_EQ(particles.attributes.size(), 3u);
    EXPECT_EQ(particles.attributes[0].name, "id");
    EXPECT_EQ(particles.attributes[0].type, ScalarType::Int32);
    EXPECT_EQ(particles.attributes[1].name, "velocity");
    EXPECT_EQ(particles.attributes[1].components, 3);
    EXPECT_EQ(particles.attributes[2].name, "pressure");
    EXPECT_EQ(particles.attributes[2].type, ScalarType::Float64);
    size_t mismatches = 0;
    for (size_t i = 0; i < count && mismatches < 5; ++i) {
        const Record r = record(i);
        const bool same = particles.positions[i] == openvdb::Vec3f(r.x, r.y, r.z) &&
            particles.attributes[0].asDouble(i) == double(r.id) &&
            particles.attributes[1].asDouble(i, 0) == double(r.z) &&
            particles.attributes[1].asDouble(i, 2) == double(r.y) &&
            particles.attributes[2].asDouble(i) == r.pressure;
        if (!same) {
            ++mismatches;
            ADD_FAILURE() << "particle " << i << ": " << particles.positions[i];
        }
    }
}

TEST_F(ReadStreamingTest, VtkLargerThanTheBufferBinaryAndAscii)
{
    for (const bool binary : {true, false}) {
        for (const std::string type : {"float", "double"}) {
            SCOPED_TRACE(std::string(binary ? "binary " : "ascii ") + type);
            const std::string bytes = makeVtk(binary, type, kManyParticles);
            ASSERT_GT(bytes.size(), size_t(1) << 20);
            writeBytes(path("big.vtk"), bytes);
            expectVtk(readParticles(path("big.vtk")), kManyParticles);
        }
    }
}

TEST_F(ReadStreamingTest, VtkTruncatedInALaterChunkNamesTheSection)
{
    const std::string bytes = makeVtk(/*binary=*/true, "double", kManyParticles);
    const std::string p = path("cut.vtk");
    auto cutAfter = [&](const std::string& header, size_t extra) {
        writeBytes(p, bytes.substr(0, bytes.find(header) + header.size() + extra));
        return fileErrorOf(p);
    };
    EXPECT_EQ(cutAfter("POINTS 150001 double\n", 3000000), "truncated POINTS section (" + p + ")");
    EXPECT_EQ(cutAfter("OFFSETS vtktypeint64\n", 1100000), "truncated CELLS section (" + p + ")");
    EXPECT_EQ(cutAfter("VECTORS velocity float\n", 1500000),
              "truncated VECTORS 'velocity' section (" + p + ")");
    writeBytes(p, bytes.substr(0, bytes.size() - 9));
    EXPECT_EQ(fileErrorOf(p), "truncated FIELD array 'pressure' (" + p + ")");
}

TEST_F(ReadStreamingTest, VtkFromAPipe)
{
    const std::string bytes = makeVtk(/*binary=*/true, "float", kManyParticles);
    readThroughFifo(path("fifo.vtk"), bytes, [&] {
        expectVtk(readParticles(path("fifo.vtk")), kManyParticles);
    });
}

TEST_F(ReadStreamingTest, RepositoryFramesReadAsTheirPlyCopies)
{
    // The same particles through the VTK reader and, rewritten, through the PLY reader.
    const ParticleSet vtk =
        readParticles(std::string(NONBLOPPY_TEST_DATA_DIR) + "/dam_break_frame_23_24389_particles.vtk");
    std::string bytes = "ply\nformat binary_big_endian 1.0\nelement vertex " +
        std::to_string(vtk.size()) + "\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n";
    for (const openvdb::Vec3f& p : vtk.positions) {
        for (int axis = 0; axis < 3; ++axis) bytes += encode(p[axis], /*bigEndian=*/true);
    }
    writeBytes(path("dam.ply"), bytes);
    const ParticleSet ply = readParticles(path("dam.ply"));
    EXPECT_EQ(ply.positions, vtk.positions);
}

// ------------------------------------------------------------------------------------------
// XYZ

TEST_F(ReadStreamingTest, XyzLargerThanTheBufferAndFromAPipe)
{
    std::string bytes;
    for (size_t i = 0; i < kManyParticles; ++i) {
        const Record r = record(i);
        bytes += encode(r.x, false) + encode(r.y, false) + encode(r.z, false);
    }
    writeBytes(path("big.xyz"), bytes);
    expectRecords(readParticles(path("big.xyz")), Layout::PackedFloat, kManyParticles);
    readThroughFifo(path("fifo.xyz"), bytes, [&] {
        expectRecords(readParticles(path("fifo.xyz")), Layout::PackedFloat, kManyParticles);
    });
}

} // namespace
