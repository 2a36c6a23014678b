// SPDX-License-Identifier: Apache-2.0
// Tests for the BGEO, VTU, CSV/TXT, JSON and VDB-points readers: real frames in tests/data
// checked against the other reader of the same frame, synthetic files in every encoding,
// and truncated, corrupt and hostile input with their exact messages.

#include "TestUtil.h"
#include "support/AllocationRecorder.h"
#include "support/OpenVdbPoints.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/ReadParticles.h>
#include <nonbloppy/WriteParticles.h>
#include <nonbloppy/WriteVdb.h>

#include <openvdb/openvdb.h>
#include <openvdb/points/PointDataGrid.h>
#include <tbb/task_arena.h>

#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <clocale>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

namespace {

using nonbloppy_test::dataPath;
using nonbloppy_test::base64;
using nonbloppy_test::readBytes;
using nonbloppy_test::writeBytes;

using nonbloppy::FileError;
using nonbloppy::ParticleAttribute;
using nonbloppy::ParticleSet;
using nonbloppy::ScalarType;
using nonbloppy::readParticles;

std::string
gunzipBytes(const std::string& compressed)
{
    z_stream stream{};
    EXPECT_EQ(inflateInit2(&stream, 16 + MAX_WBITS), Z_OK);
    std::string out(compressed.size() * 20, '\0');
    stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(compressed.data()));
    stream.avail_in = uInt(compressed.size());
    stream.next_out = reinterpret_cast<Bytef*>(out.data());
    stream.avail_out = uInt(out.size());
    EXPECT_EQ(inflate(&stream, Z_FINISH), Z_STREAM_END);
    out.resize(stream.total_out);
    inflateEnd(&stream);
    return out;
}

std::string
zlibBytes(const std::string& raw)
{
    uLongf size = compressBound(uLong(raw.size()));
    std::string out(size, '\0');
    EXPECT_EQ(compress(reinterpret_cast<Bytef*>(out.data()), &size,
                       reinterpret_cast<const Bytef*>(raw.data()), uLong(raw.size())), Z_OK);
    out.resize(size);
    return out;
}

template<typename T>
std::string
bytesOf(T value, bool bigEndian = false)
{
    std::string bytes(sizeof(T), '\0');
    std::memcpy(bytes.data(), &value, sizeof(T));
    if (bigEndian) std::reverse(bytes.begin(), bytes.end());
    return bytes;
}

/// Each test in a fresh directory; write() is ScratchDirTest's.
class ReadFormatsTest : public nonbloppy_test::ScratchDirTest
{
};

/// The FileError message readParticles(@a path) throws ("" if none).
std::string
fileErrorOf(const std::string& path)
{
    return nonbloppy_test::messageOf<FileError>([&] { readParticles(path); });
}

using nonbloppy_test::attribute;

void
expectSameParticles(const ParticleSet& a, const ParticleSet& b, bool compareAttributes = true)
{
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a.positions[i], b.positions[i]) << "particle " << i;
    }
    if (!compareAttributes) return;
    ASSERT_EQ(a.attributes.size(), b.attributes.size());
    for (size_t k = 0; k < a.attributes.size(); ++k) {
        EXPECT_EQ(a.attributes[k].name, b.attributes[k].name);
        EXPECT_EQ(a.attributes[k].type, b.attributes[k].type) << a.attributes[k].name;
        EXPECT_EQ(a.attributes[k].components, b.attributes[k].components) << a.attributes[k].name;
        EXPECT_TRUE(a.attributes[k].bytes == b.attributes[k].bytes) << a.attributes[k].name;
    }
}

// ---------------------------------------------------------------------------------------
// BGEO

TEST_F(ReadFormatsTest, BgeoFrame9HasItsParticlesAndAttributes)
{
    const ParticleSet particles = readParticles(dataPath("dam_break_frame_9_6859_particles.bgeo"));
    ASSERT_EQ(particles.size(), 6859u);
    ASSERT_EQ(particles.attributes.size(), 3u);
    const ParticleAttribute& id = attribute(particles, "id");
    EXPECT_EQ(id.type, ScalarType::Int32);
    EXPECT_EQ(id.components, 1);
    EXPECT_EQ(attribute(particles, "density").type, ScalarType::Float32);
    const ParticleAttribute& velocity = attribute(particles, "velocity");
    EXPECT_EQ(velocity.type, ScalarType::Float32);
    EXPECT_EQ(velocity.components, 3);
    EXPECT_EQ(velocity.size(), 6859u);

    // The first point as the decompressed bytes spell it (big-endian float bits).
    auto fromBits = [](uint32_t bits) { float f; std::memcpy(&f, &bits, 4); return f; };
    EXPECT_EQ(particles.positions[0], openvdb::Vec3f(fromBits(0xbff4823a), fromBits(0x3d70357b),
                                                      fromBits(0x3e21aeee)));
    EXPECT_EQ(id.asDouble(0), 30.0);
    EXPECT_EQ(float(attribute(particles, "density").asDouble(0)), fromBits(0x447a083b));
    // Ids are a permutation of 0..N-1.
    std::vector<int> ids(particles.size());
    for (size_t i = 0; i < ids.size(); ++i) ids[i] = int(id.asDouble(i));
    std::sort(ids.begin(), ids.end());
    for (size_t i = 0; i < ids.size(); ++i) ASSERT_EQ(ids[i], int(i));
}

TEST_F(ReadFormatsTest, BgeoFrame23MatchesTheVtkOfTheSameFrame)
{
    const ParticleSet bgeo = readParticles(dataPath("dam_break_frame_23_24389_particles.bgeo"));
    const ParticleSet vtk = readParticles(dataPath("dam_break_frame_23_24389_particles.vtk"));
    ASSERT_EQ(bgeo.size(), 24389u);
    expectSameParticles(bgeo, vtk, /*compareAttributes=*/false);
}

TEST_F(ReadFormatsTest, BgeoUncompressedReadsTheSame)
{
    const std::string gz = dataPath("dam_break_frame_9_6859_particles.bgeo");
    const std::string plain = write("plain.bgeo", gunzipBytes(readBytes(gz)));
    expectSameParticles(readParticles(plain), readParticles(gz));
}

// Houdini 12 and later write the classic layout as .bhclassic (their .bgeo is JSON-based),
// and gzip it under .gz; .bgeo.sc (Blosc, Houdini's default cache) and ASCII .geo are not
// read, and the message says which name to write instead.
TEST_F(ReadFormatsTest, BgeoUnderHoudiniClassicNames)
{
    const std::string gz = dataPath("dam_break_frame_9_6859_particles.bgeo");
    const ParticleSet expected = readParticles(gz);
    const std::string bytes = readBytes(gz);
    for (const char* name : {"frame.bhclassic", "frame.bgeo.gz", "frame.BHCLASSIC.GZ", "frame.0009.bhclassic.gz"}) {
        const std::string path = write(name, bytes);
        EXPECT_TRUE(nonbloppy::isParticleFile(path)) << name;
        expectSameParticles(readParticles(path), expected);
    }
    const std::string plain = write("plain.bhclassic", gunzipBytes(bytes));
    expectSameParticles(readParticles(plain), expected);

    const std::string blosc = write("frame.bgeo.sc", bytes);
    EXPECT_FALSE(nonbloppy::isParticleFile(blosc));
    EXPECT_EQ(fileErrorOf(blosc), "unknown particle file extension '.sc' (" + blosc + "): Houdini's Blosc-compressed "
                                  "geometry is not read; export it from Houdini as .bhclassic (classic binary geometry; "
                                  "renaming does not convert it)");
    const std::string ascii = write("frame.geo", "PGEOMETRY V5\n");
    EXPECT_EQ(fileErrorOf(ascii), "unknown particle file extension '.geo' (" + ascii + "): Houdini's ASCII geometry "
                                  "is not read; export it from Houdini as .bhclassic (classic binary geometry; renaming does "
                                  "not convert it)");
    const std::string tarball = write("frame.tar.gz", bytes);
    EXPECT_FALSE(nonbloppy::isParticleFile(tarball));
    EXPECT_EQ(fileErrorOf(tarball), "unknown particle file extension '.gz' (" + tarball + "); expected .vtk, .vtu, "
                                    ".vtp, .ply, .xyz, .bgeo, .vdb, .csv, .txt or .json");
}

TEST_F(ReadFormatsTest, BgeoTruncatedCorruptAndUnsupported)
{
    const std::string raw = gunzipBytes(readBytes(dataPath("dam_break_frame_9_6859_particles.bgeo")));
    // Header (41 bytes) + attribute table: "id" 2+2+2+4+4, "density" 2+7+2+4+4, "velocity" 2+8+2+4+12.
    const size_t tableEnd = 41 + 14 + 19 + 28;
    const std::string cut = write("cut.bgeo", raw.substr(0, tableEnd + 1000));
    EXPECT_EQ(fileErrorOf(cut), "truncated BGEO points: header claims 6859 points of 36 bytes, 1000 "
                                "bytes left (" + cut + ")");
    const std::string inTable = write("table.bgeo", raw.substr(0, 50));
    EXPECT_EQ(fileErrorOf(inTable), "truncated BGEO attribute table (" + inTable + ")");
    const std::string header = write("header.bgeo", raw.substr(0, 20));
    EXPECT_EQ(fileErrorOf(header), "truncated BGEO header (" + header + ")");

    const std::string gz = readBytes(dataPath("dam_break_frame_9_6859_particles.bgeo"));
    const std::string cutGz = write("cutgz.bgeo", gz.substr(0, gz.size() / 2));
    EXPECT_EQ(fileErrorOf(cutGz), "truncated gzip data (" + cutGz + ")");
    std::string flipped = gz;
    for (size_t i = 100; i < 200; ++i) flipped[i] = char(~flipped[i]);
    const std::string corrupt = write("corrupt.bgeo", flipped);
    EXPECT_EQ(fileErrorOf(corrupt).rfind("corrupt gzip data: ", 0), 0u) << fileErrorOf(corrupt);

    std::string v6 = raw;
    v6[8] = 6;
    const std::string version6 = write("v6.bgeo", v6);
    EXPECT_EQ(fileErrorOf(version6), "unsupported BGEO version (6) (" + version6 + ")");
    const std::string json = write("json.bgeo", "[\"fileversion\",\"19.0.383\",\"hasindex\",false]");
    EXPECT_EQ(fileErrorOf(json), "unsupported BGEO version (JSON-based, Houdini 12 or later); only "
                                 "the classic binary BgeoV layout is read: export it from Houdini as .bhclassic (" + json + ")");
    const std::string binaryJson = write("bjson.bgeo", std::string("\x7fNSJb", 5) + "\x01");
    EXPECT_EQ(fileErrorOf(binaryJson), "unsupported BGEO version (JSON-based, Houdini 12 or later); only the "
                                       "classic binary BgeoV layout is read: export it from Houdini as .bhclassic (" + binaryJson + ")");
    const std::string other = write("other.bgeo", "hello world");
    EXPECT_EQ(fileErrorOf(other), "not a BGEO file (no 'BgeoV' magic) (" + other + ")");
}

TEST_F(ReadFormatsTest, BgeoHostileCountIsRejectedBeforeAllocating)
{
    std::string bytes = "BgeoV" + bytesOf<int32_t>(5, true) + bytesOf<int32_t>(1000000000, true);
    for (int i = 0; i < 7; ++i) bytes += bytesOf<int32_t>(0, true);
    bytes += std::string(1000, '\0');
    const std::string hostile = write("hostile.bgeo", bytes);
    std::string message;
    // 16 GB claimed: refused before any allocation for them (the largest request, the
    // reader's own buffer, stays under 2 MiB).
    EXPECT_LT(nonbloppy_test::largestAllocationDuring([&] { message = fileErrorOf(hostile); }), size_t(2) << 20);
    EXPECT_EQ(message, "truncated BGEO points: header claims 1000000000 points of 16 "
                       "bytes, 1000 bytes left (" + hostile + ")");
    // A gzip stream expanding far beyond its size is inflated in chunks, never whole.
    std::string bomb = "BgeoV" + bytesOf<int32_t>(5, true) + bytesOf<int32_t>(0, true);
    for (int i = 0; i < 7; ++i) bomb += bytesOf<int32_t>(0, true);
    bomb += std::string(50u << 20, '\0');
    uLongf size = compressBound(uLong(bomb.size()));
    std::string deflated(size, '\0');
    z_stream stream{};
    ASSERT_EQ(deflateInit2(&stream, 9, Z_DEFLATED, 16 + MAX_WBITS, 9, Z_DEFAULT_STRATEGY), Z_OK);
    stream.next_in = reinterpret_cast<Bytef*>(bomb.data());
    stream.avail_in = uInt(bomb.size());
    stream.next_out = reinterpret_cast<Bytef*>(deflated.data());
    stream.avail_out = uInt(deflated.size());
    ASSERT_EQ(deflate(&stream, Z_FINISH), Z_STREAM_END);
    deflated.resize(stream.total_out);
    deflateEnd(&stream);
    // 50 MB of zeros deflate to ~50 KB: within deflate's ratio, so it is read (0 points).
    const std::string zeros = write("zeros.bgeo", deflated);
    size_t points = 1;
    EXPECT_LT(nonbloppy_test::largestAllocationDuring([&] { points = readParticles(zeros).size(); }), size_t(2) << 20);
    EXPECT_EQ(points, 0u);
}

// ---------------------------------------------------------------------------------------
// VTU

TEST_F(ReadFormatsTest, VtuCubeMatchesTheLegacyVtk)
{
    const ParticleSet vtu = readParticles(dataPath("cube_8_particles.vtu"));
    const ParticleSet vtk = readParticles(dataPath("cube_8_particles.vtk"));
    ASSERT_EQ(vtu.size(), 8u);
    expectSameParticles(vtu, vtk, /*compareAttributes=*/false);
    ASSERT_EQ(vtu.attributes.size(), 4u);
    EXPECT_EQ(vtu.attributes[0].name, "velocity");
    EXPECT_EQ(vtu.attributes[0].type, ScalarType::Float64);
    EXPECT_EQ(vtu.attributes[0].components, 3);
    EXPECT_EQ(vtu.attributes[1].name, "pressure");
    EXPECT_EQ(vtu.attributes[2].name, "density");
    EXPECT_EQ(vtu.attributes[3].name, "index");
    EXPECT_EQ(vtu.attributes[3].type, ScalarType::Int64);
    for (const ParticleAttribute& a : vtu.attributes) EXPECT_EQ(a.size(), 8u) << a.name;
}

TEST_F(ReadFormatsTest, VtuCompressedAndBase64FluidAgree)
{
    const ParticleSet compressed = readParticles(dataPath("fluid_250_particles.vtu"));
    const ParticleSet encoded = readParticles(dataPath("fluid_encoded_250_particles.vtu"));
    ASSERT_EQ(compressed.size(), 250u);
    expectSameParticles(compressed, encoded);
    const ParticleAttribute& index = attribute(compressed, "index");
    std::vector<int64_t> ids;
    for (size_t i = 0; i < 250; ++i) ids.push_back(int64_t(index.asDouble(i)));
    std::sort(ids.begin(), ids.end());
    EXPECT_EQ(ids.front(), 1);
    EXPECT_EQ(ids.back(), 250);
}

/// A VTU of three particles (positions (i, 2i, 3i)/4) and an Int32 "id" = 10 + i, in the
/// given encoding.
struct VtuVariant
{
    std::string format = "appended";  ///< ascii, binary, appended
    std::string encoding = "raw";     ///< appended: raw or base64
    bool zlib = false, uint64Header = false, bigEndian = false, float64 = false;
    bool jointBase64 = false;         ///< one base64 segment for header and data
};

std::string
makeVtu(const VtuVariant& v)
{
    auto number = [&](auto value) { return bytesOf(value, v.bigEndian); };
    auto headerWord = [&](uint64_t value) {
        return v.uint64Header ? number(uint64_t(value)) : number(uint32_t(value));
    };
    std::string points, ids, pointsText, idsText;
    for (int i = 0; i < 3; ++i) {
        for (int a = 1; a <= 3; ++a) {
            const double value = i * a / 4.0;
            points += v.float64 ? number(value) : number(float(value));
            pointsText += std::to_string(value) + " ";
        }
        ids += number(int32_t(10 + i));
        idsText += std::to_string(10 + i) + " ";
    }
    // [header][data] blocks as VTK writes them; for base64 the header and data are two
    // padded segments unless jointBase64.
    auto block = [&](const std::string& raw, bool encode) {
        std::string header, data;
        if (v.zlib) {
            data = zlibBytes(raw);
            header = headerWord(1) + headerWord(raw.size()) + headerWord(raw.size()) + headerWord(data.size());
        } else {
            header = headerWord(raw.size());
            data = raw;
        }
        if (!encode) return header + data;
        return v.jointBase64 ? base64(header + data) : base64(header) + base64(data);
    };
    std::string appended;
    auto dataArray = [&](const std::string& type, const std::string& name, int components,
                         const std::string& raw, const std::string& text) {
        std::string xml = "<DataArray type=\"" + type + "\" Name=\"" + name +
                          "\" NumberOfComponents=\"" + std::to_string(components) + "\" format=\"" + v.format + "\"";
        if (v.format == "appended") {
            xml += " offset=\"" + std::to_string(appended.size()) + "\"/>\n";
            appended += block(raw, v.encoding == "base64");
        } else if (v.format == "binary") {
            xml += ">\n" + block(raw, true) + "\n</DataArray>\n";
        } else {
            xml += ">\n" + text + "\n</DataArray>\n";
        }
        return xml;
    };
    std::string body = "<Piece NumberOfPoints=\"3\" NumberOfCells=\"0\">\n<Points>\n";
    body += dataArray(v.float64 ? "Float64" : "Float32", "Points", 3, points, pointsText);
    body += "</Points>\n<PointData>\n";
    body += dataArray("Int32", "id", 1, ids, idsText);
    body += "</PointData>\n</Piece>\n";
    std::string xml = "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"";
    xml += v.bigEndian ? "BigEndian" : "LittleEndian";
    xml += std::string("\" header_type=\"") + (v.uint64Header ? "UInt64" : "UInt32") + "\"";
    if (v.zlib) xml += " compressor=\"vtkZLibDataCompressor\"";
    xml += ">\n<UnstructuredGrid>\n" + body + "</UnstructuredGrid>\n";
    if (v.format == "appended") {
        xml += "<AppendedData encoding=\"" + v.encoding + "\">\n_" + appended + "\n</AppendedData>\n";
    }
    return xml + "</VTKFile>\n";
}

void
expectThreeParticles(const ParticleSet& particles, const std::string& label)
{
    ASSERT_EQ(particles.size(), 3u) << label;
    for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(particles.positions[i], openvdb::Vec3f(i / 4.0f, 2 * i / 4.0f, 3 * i / 4.0f)) << label;
    }
    ASSERT_EQ(particles.attributes.size(), 1u) << label;
    EXPECT_EQ(particles.attributes[0].name, "id");
    EXPECT_EQ(particles.attributes[0].type, ScalarType::Int32);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(particles.attributes[0].asDouble(i), 10 + i) << label;
}

TEST_F(ReadFormatsTest, VtuEveryEncoding)
{
    int n = 0;
    for (const std::string format : {"ascii", "binary", "appended"}) {
        for (const std::string encoding : {"raw", "base64"}) {
            if (format != "appended" && encoding == "base64") continue;
            for (int flags = 0; flags < 32; ++flags) {
                VtuVariant v;
                v.format = format;
                v.encoding = encoding;
                v.zlib = flags & 1;
                v.uint64Header = flags & 2;
                v.bigEndian = flags & 4;
                v.float64 = flags & 8;
                v.jointBase64 = flags & 16;
                if (format == "ascii" && (v.zlib || v.uint64Header || v.jointBase64)) continue;
                const std::string label = format + "/" + encoding + "/" + std::to_string(flags);
                const std::string file = write("v" + std::to_string(n++) + ".vtu", makeVtu(v));
                expectThreeParticles(readParticles(file), label);
            }
        }
    }
    EXPECT_EQ(n, 4 + 32 + 32 + 32);
}

TEST_F(ReadFormatsTest, VtuTruncatedCorruptAndHostile)
{
    const std::string fluid = readBytes(dataPath("fluid_250_particles.vtu"));
    const std::string half = write("half.vtu", fluid.substr(0, fluid.size() / 2));
    EXPECT_EQ(fileErrorOf(half), "truncated AppendedData (no </AppendedData>) (" + half + ")");
    const std::string noXml = write("noxml.vtu", fluid.substr(0, 300));
    EXPECT_EQ(fileErrorOf(noXml).rfind("XML error at byte ", 0), 0u) << fileErrorOf(noXml);
    // Expat has no position in an empty document (-1, printed as 18446744073709551615).
    const std::string empty = write("empty.vtu", "");
    EXPECT_EQ(fileErrorOf(empty), "XML error at byte 0: no element found (" + empty + ")");

    VtuVariant v;
    v.zlib = true;
    std::string text = makeVtu(v);
    const size_t data = text.find("\n_") + 2 + 16;  // inside the first zlib stream
    text[data + 2] = char(~text[data + 2]);
    text[data + 3] = char(~text[data + 3]);
    const std::string corrupt = write("corrupt.vtu", text);
    EXPECT_EQ(fileErrorOf(corrupt).rfind("corrupt compressed data in block 0 of Points", 0), 0u)
        << fileErrorOf(corrupt);

    v = VtuVariant();
    text = makeVtu(v);
    const size_t count = text.find("NumberOfPoints=\"3\"");
    text.replace(count, 18, "NumberOfPoints=\"1000000000\"");
    const std::string hostile = write("hostile.vtu", text);
    EXPECT_EQ(fileErrorOf(hostile), "truncated Points: the file is too small for 1000000000 tuples (" +
                                        hostile + ")");

    v = VtuVariant();
    v.format = "binary";
    text = makeVtu(v);
    const size_t b64 = text.find("format=\"binary\">\n") + 17;
    text[b64 + 5] = '*';
    const std::string badChar = write("badchar.vtu", text);
    EXPECT_EQ(fileErrorOf(badChar).rfind("invalid base64 character '*'", 0), 0u) << fileErrorOf(badChar);

    v = VtuVariant();
    v.format = "ascii";
    text = makeVtu(v);
    text.replace(text.find("10 11 12"), 8, "10 xx 12");
    const std::string badNumber = write("badnumber.vtu", text);
    EXPECT_EQ(fileErrorOf(badNumber), "bad value 'xx' in 'id' (" + badNumber + ")");

    const std::string lz4 = write("lz4.vtu", "<VTKFile type=\"UnstructuredGrid\" compressor=\"vtkLZ4DataCompressor\"/>");
    EXPECT_EQ(fileErrorOf(lz4), "unsupported compressor 'vtkLZ4DataCompressor'; only "
                                "vtkZLibDataCompressor is read (" + lz4 + ")");
    const std::string image = write("image.vtu", "<VTKFile type=\"ImageData\"/>");
    EXPECT_EQ(fileErrorOf(image), "unsupported VTKFile type 'ImageData'; expected UnstructuredGrid "
                                  "or PolyData (" + image + ")");
}

// ---------------------------------------------------------------------------------------
// CSV, TXT, JSON

TEST_F(ReadFormatsTest, CsvWithVectorAndScalarColumns)
{
    const std::string file = write("p.csv",
        "# exported by a test\n"
        "\"Points:0\",\"Points:1\",\"Points:2\",\"velocity:0\",\"velocity:1\",\"velocity:2\",id,density\n"
        "0.5,1,1.5,1,2,3,7,1000.5\n"
        "\n"
        "-1,-2,-3e-1,4,5,6,8,999\n");
    const ParticleSet particles = readParticles(file);
    ASSERT_EQ(particles.size(), 2u);
    EXPECT_EQ(particles.positions[0], openvdb::Vec3f(0.5f, 1.0f, 1.5f));
    EXPECT_EQ(particles.positions[1], openvdb::Vec3f(-1.0f, -2.0f, -0.3f));
    ASSERT_EQ(particles.attributes.size(), 3u);
    const ParticleAttribute& velocity = attribute(particles, "velocity");
    EXPECT_EQ(velocity.components, 3);
    EXPECT_EQ(velocity.type, ScalarType::Int64);  // every value an integer
    EXPECT_EQ(velocity.asDouble(1, 2), 6.0);
    EXPECT_EQ(attribute(particles, "id").type, ScalarType::Int64);
    EXPECT_EQ(attribute(particles, "id").asDouble(1), 8.0);
    EXPECT_EQ(attribute(particles, "density").type, ScalarType::Float64);
    EXPECT_EQ(attribute(particles, "density").asDouble(0), 1000.5);
}

TEST_F(ReadFormatsTest, CsvIntegersAreExactPast2To53)
{
    // Whole numbers were parsed as doubles and a column was int64 only below 9e15: the id
    // 9007199254740993 (2^53 + 1) came back as ...992, a neighbour's. Now parsed as int64;
    // uint64 past int64 where no value is negative (a uint64 id past 2^63 came back
    // rounded, bug hunt); a column turns float64 at its first value that fits neither.
    const std::string file = write("ids.csv",
        "x,y,z,id,mixed,beyond,signed,unsigned\n"
        "0,0,0,9007199254740993,9007199254740993,9223372036854775807,-1,18446744073709551615\n"
        "1,0,0,-9223372036854775808,2.5,18446744073709551614,9223372036854775808,-1\n");
    const ParticleSet particles = readParticles(file);
    ASSERT_EQ(particles.size(), 2u);
    const ParticleAttribute& id = attribute(particles, "id");
    ASSERT_EQ(id.type, ScalarType::Int64);
    int64_t values[2];
    std::memcpy(values, id.bytes.data(), sizeof(values));
    EXPECT_EQ(values[0], 9007199254740993);
    EXPECT_EQ(values[1], std::numeric_limits<int64_t>::min());
    const ParticleAttribute& mixed = attribute(particles, "mixed");
    EXPECT_EQ(mixed.type, ScalarType::Float64);
    EXPECT_EQ(mixed.asDouble(0), 9007199254740992.0);  // the nearest double
    EXPECT_EQ(mixed.asDouble(1), 2.5);
    const ParticleAttribute& beyond = attribute(particles, "beyond");
    ASSERT_EQ(beyond.type, ScalarType::UInt64);
    uint64_t large[2];
    std::memcpy(large, beyond.bytes.data(), sizeof(large));
    EXPECT_EQ(large[0], 9223372036854775807u);
    EXPECT_EQ(large[1], 18446744073709551614u);
    const ParticleAttribute& signedThenLarge = attribute(particles, "signed");
    EXPECT_EQ(signedThenLarge.type, ScalarType::Float64);
    EXPECT_EQ(signedThenLarge.asDouble(0), -1.0);
    EXPECT_EQ(signedThenLarge.asDouble(1), 9223372036854775808.0);
    const ParticleAttribute& largeThenNegative = attribute(particles, "unsigned");
    EXPECT_EQ(largeThenNegative.type, ScalarType::Float64);
    EXPECT_EQ(largeThenNegative.asDouble(0), 18446744073709551615.0);
    EXPECT_EQ(largeThenNegative.asDouble(1), -1.0);
}

TEST_F(ReadFormatsTest, CsvWithAByteOrderMarkAsExcelWritesIt)
{
    // Excel's "CSV UTF-8" starts with EF BB BF: the header read '\xef\xbb\xbfx,y,z' and was
    // refused for naming no column x.
    for (const std::string& first : {std::string(""), std::string("# comment\n")}) {
        const std::string file = write("bom.csv", "\xef\xbb\xbf" + first + "x,y,z,temp\n1,2,3,20.5\n");
        const ParticleSet particles = readParticles(file);
        ASSERT_EQ(particles.size(), 1u);
        EXPECT_EQ(particles.positions[0], openvdb::Vec3f(1.0f, 2.0f, 3.0f));
        EXPECT_EQ(attribute(particles, "temp").asDouble(0), 20.5);
    }
}

TEST_F(ReadFormatsTest, CsvFromPandasAndRWithTheirRowNumbersAndQuotes)
{
    // pandas' to_csv() and R's write.csv() put the row numbers first, under no name: the
    // file was refused ("empty column name"). A quoted name holding the separator was
    // split in two ("line 2 has 4 fields, the header 5").
    const std::string pandas = write("pandas.csv", ",x,y,z,speed\n0,0.5,0,0,1.5\n1,1,2,3,2.5\n");
    const std::string r = write("r.csv", "\"\",\"x\",\"y\",\"z\",\"a,b\"\n\"1\",0.5,0,0,7\n\"2\",1,2,3,8\n");
    for (const std::string& file : {pandas, r}) {
        const ParticleSet particles = readParticles(file);
        ASSERT_EQ(particles.size(), 2u) << file;
        EXPECT_EQ(particles.positions[1], openvdb::Vec3f(1.0f, 2.0f, 3.0f)) << file;
        ASSERT_EQ(particles.attributes.size(), 1u) << file;
        EXPECT_EQ(particles.skipped, std::vector<std::string>{"unnamed column 1"}) << file;
    }
    EXPECT_EQ(attribute(readParticles(pandas), "speed").asDouble(1), 2.5);
    EXPECT_EQ(attribute(readParticles(r), "a,b").asDouble(1), 8.0);
    // The separator is the first found outside quotes (',' inside "a,b" chose the comma).
    const std::string semicolons = write("semi.csv", "x;y;z;\"a,b\"\n0;0;0;1,5\n");
    EXPECT_EQ(fileErrorOf(semicolons), "bad number '1,5' on line 2 (" + semicolons + ")");
}

TEST_F(ReadFormatsTest, CsvNamesWithQuotesAndCommasRoundTripExactly)
{
    // A doubled quote inside a quoted name (RFC 4180: "e""f" names e"f) stayed doubled, and
    // the writer gave a name's '"' and ',' as '_' (renamed, with a warning) where quoting
    // the name keeps it (format round-trip hunt).
    const ParticleSet read = readParticles(write("quoted.csv", "x,y,z,\"e\"\"f\",\"a,b\",\"\"\"\"\n0,0,0,1,2,3\n"));
    std::vector<std::string> names;
    for (const ParticleAttribute& a : read.attributes) names.push_back(a.name);
    EXPECT_EQ(names, (std::vector<std::string>{"e\"f", "a,b", "\""}));

    ParticleSet particles;
    particles.positions = {openvdb::Vec3f(0.0f), openvdb::Vec3f(1.0f, 2.0f, 3.0f)};
    const std::vector<std::string> awkward = {"e\"f", "a,b", "\"q\"", "'s'", "\"", "c,\"d\"", "v,\"w\""};
    for (size_t i = 0; i + 1 < awkward.size(); ++i) {
        particles.attributes.push_back(ParticleAttribute::of(awkward[i], 1, std::vector<double>{0.5 + double(i), -1.0}));
    }
    particles.attributes.push_back(ParticleAttribute::of(awkward.back(), 3, std::vector<double>{1, 2, 3, 4, 5, 6}));
    const std::string file = path("awkward.csv");
    EXPECT_EQ(nonbloppy::writtenAttributeNames(particles, file), awkward);
    nonbloppy::writeParticles(particles, file);
    const std::string header = "x,y,z,\"e\"\"f\",\"a,b\",\"\"\"q\"\"\",\"'s'\",\"\"\"\",\"c,\"\"d\"\"\","
                               "\"v,\"\"w\"\":0\",\"v,\"\"w\"\":1\",\"v,\"\"w\"\":2\"\n";
    EXPECT_EQ(readBytes(file).substr(0, header.size()), header);
    expectSameParticles(readParticles(file), particles);
}

TEST_F(ReadFormatsTest, CsvComponentSpellingsFormVectorsOnlyWhenTheyAreOne)
{
    // speed_x alone is a scalar of that name (it was read as a 1-component "speed", so a
    // scalar so named did not survive a CSV round trip); w beside w_x,w_y,w_z keeps the
    // three as columns of their own (they were a duplicate "w"); a_x,a_y is 2 components.
    const std::string file = write("c.csv", "x,y,z,speed_x,w,w_x,w_y,w_z,a_x,a_y,b[1],n.x\n"
                                            "1,2,3,4,5,6,7,8,9,10,11,12\n");
    const ParticleSet particles = readParticles(file);
    ASSERT_EQ(particles.size(), 1u);
    std::vector<std::string> names;
    for (const ParticleAttribute& a : particles.attributes) names.push_back(a.name + "/" + std::to_string(a.components));
    EXPECT_EQ(names, (std::vector<std::string>{"speed_x/1", "w/1", "w_x/1", "w_y/1", "w_z/1", "a/2", "b[1]/1",
                                               "n.x/1"}));
    EXPECT_EQ(attribute(particles, "w_z").asDouble(0), 8.0);
    EXPECT_EQ(attribute(particles, "a").asDouble(0, 1), 10.0);
    EXPECT_EQ(attribute(particles, "n.x").asDouble(0), 12.0);
    // A column named twice is still an error.
    const std::string twice = write("twice.csv", "x,y,z,m,m\n1,2,3,4,5\n");
    EXPECT_EQ(fileErrorOf(twice), "duplicate column 'm' (" + twice + ")");
}

TEST_F(ReadFormatsTest, PlyVectorPropertiesAreOneAttribute)
{
    // As writeParticles() spells vectors: v_x,v_y,v_z and c_0..c_3, each of one type. A
    // lone speed_x, and w_x,w_y of two types, stay properties of their own.
    const std::string file = write("v.ply",
        "ply\nformat ascii 1.0\nelement vertex 2\n"
        "property float x\nproperty float y\nproperty float z\n"
        "property float speed_x\nproperty float v_x\nproperty float v_y\nproperty float v_z\n"
        "property float w_x\nproperty int w_y\n"
        "property uchar c_0\nproperty uchar c_1\nproperty uchar c_2\nproperty uchar c_3\nend_header\n"
        "1 2 3 4 5 6 7 8 9 10 11 12 13\n"
        "-1 -2 -3 -4 -5 -6 -7 -8 -9 20 21 22 23\n");
    const ParticleSet particles = readParticles(file);
    ASSERT_EQ(particles.size(), 2u);
    EXPECT_EQ(particles.positions[1], openvdb::Vec3f(-1, -2, -3));
    std::vector<std::string> names;
    for (const ParticleAttribute& a : particles.attributes) names.push_back(a.name + "/" + std::to_string(a.components));
    EXPECT_EQ(names, (std::vector<std::string>{"speed_x/1", "v/3", "w_x/1", "w_y/1", "c/4"}));
    const ParticleAttribute& v = attribute(particles, "v");
    EXPECT_EQ(v.type, ScalarType::Float32);
    EXPECT_EQ(v.asDouble(0, 0), 5.0);
    EXPECT_EQ(v.asDouble(1, 2), -7.0);
    EXPECT_EQ(attribute(particles, "w_y").type, ScalarType::Int32);
    const ParticleAttribute& c = attribute(particles, "c");
    EXPECT_EQ(c.type, ScalarType::UInt8);
    EXPECT_EQ(c.asDouble(1, 3), 23.0);
    EXPECT_EQ(c.asDouble(0, 1), 11.0);
}

TEST_F(ReadFormatsTest, TxtWithSpacesAndAnyColumnOrder)
{
    const std::string file = write("p.txt", "id  Z y X\n1 3 2 1\n2\t6 5 4\n");
    const ParticleSet particles = readParticles(file);
    ASSERT_EQ(particles.size(), 2u);
    EXPECT_EQ(particles.positions[0], openvdb::Vec3f(1, 2, 3));
    EXPECT_EQ(particles.positions[1], openvdb::Vec3f(4, 5, 6));
    EXPECT_EQ(attribute(particles, "id").asDouble(1), 2.0);
}

TEST_F(ReadFormatsTest, TableErrors)
{
    const std::string noZ = write("noz.csv", "x,y,w\n1,2,3\n");
    EXPECT_EQ(fileErrorOf(noZ), "the header must name columns x, y and z, got 'x,y,w' (" + noZ + ")");
    const std::string bad = write("bad.csv", "x,y,z\n1,2,3\n1,2,abc\n");
    EXPECT_EQ(fileErrorOf(bad), "bad number 'abc' on line 3 (" + bad + ")");
    const std::string fields = write("fields.csv", "x,y,z\n1,2\n");
    EXPECT_EQ(fileErrorOf(fields), "line 2 has 2 fields, the header 3 (" + fields + ")");
    const std::string empty = write("empty.csv", "# nothing\n");
    EXPECT_EQ(fileErrorOf(empty), "empty table: no header row (" + empty + ")");
}

TEST_F(ReadFormatsTest, JsonPointList)
{
    const std::string file = write("p.json", " [[1, 2, 3], [4.5, -5e-1, 6]]\n");
    const ParticleSet particles = readParticles(file);
    ASSERT_EQ(particles.size(), 2u);
    EXPECT_EQ(particles.positions[0], openvdb::Vec3f(1, 2, 3));
    EXPECT_EQ(particles.positions[1], openvdb::Vec3f(4.5f, -0.5f, 6));
    EXPECT_EQ(readParticles(write("e.json", "[]")).size(), 0u);

    const std::string two = write("two.json", "[[1,2,3],[1,2]]");
    EXPECT_EQ(fileErrorOf(two), "bad JSON particle list: particle 1 has 2 coordinates, expected 3 (" + two + ")");
    const std::string deep = write("deep.json", std::string(100000, '[') + std::string(100000, ']'));
    EXPECT_EQ(fileErrorOf(deep), "bad JSON particle list: arrays nested deeper than [[x, y, z], ...] (" + deep + ")");
    const std::string text = write("text.json", "[[0,0,0],[0.1,0,0],[0,0.1,\"3\"]]");
    EXPECT_EQ(fileErrorOf(text), "bad JSON particle list: string where a coordinate was expected (coordinate 2 of "
                                 "particle 2) (" + text + ")");
    const std::string object = write("object.json", "{\"x\": 1}");
    EXPECT_EQ(fileErrorOf(object), "bad JSON particle list: object where an array was expected (" + object + ")");
    const std::string cut = write("cut.json", "[[1,2,3],[4,");
    EXPECT_EQ(fileErrorOf(cut).rfind("bad JSON particle list: parse error at line 1, column 13", 0), 0u)
        << fileErrorOf(cut);
}

TEST_F(ReadFormatsTest, CoordinatesBeyondFloatAreNamedWithTheirText)
{
    // Positions are float: a finite 1e39 became +inf and was refused as a "non-finite
    // position of particle 2", which the file does not hold (hostile-input audit).
    const std::string csv = write("big.csv", "x,y,z\n0,0,0\n0,-3.5e38,1\n");
    EXPECT_EQ(fileErrorOf(csv), "coordinate -3.5e38 on line 3 lies outside float's range (-3.4e38 to 3.4e38) (" + csv + ")");
    const std::string json = write("big.json", "[[0,0,0],[1e39,0,0]]");
    EXPECT_EQ(fileErrorOf(json), "bad JSON particle list: coordinate 1e+39 of particle 1 lies outside float's range "
                                 "(-3.4e38 to 3.4e38) (" + json + ")");
    // Float's largest value itself, and a CSV attribute beyond float (kept as double), read.
    const ParticleSet edge = readParticles(write("edge.csv", "x,y,z,v\n3.4028234e38,0,0,1e300\n"));
    ASSERT_EQ(edge.size(), 1u);
    EXPECT_EQ(edge.positions[0][0], 3.4028234e38f);
}

TEST_F(ReadFormatsTest, MinusZeroKeepsItsSignInJsonAndCsv)
{
    // nlohmann's SAX parser hands the integer -0 to number_integer() as 0, its text gone: a
    // JSON coordinate -0 came back +0 while -0.0 kept its sign (format round-trip hunt). A
    // CSV column's "-0" lost its sign alike when a later value made the column float; a
    // column that stays integer holds 0, there being no integer -0.
    const ParticleSet json = readParticles(write("zero.json", "[[-0, 0, -0.0], [0,-0e0,-0\n], [-0,-0,-0]]"));
    ASSERT_EQ(json.size(), 3u);
    const bool negative[3][3] = {{true, false, true}, {false, true, true}, {true, true, true}};
    for (size_t n = 0; n < 3; ++n) {
        for (int a = 0; a < 3; ++a) {
            EXPECT_EQ(json.positions[n][a], 0.0f) << n << " " << a;
            EXPECT_EQ(std::signbit(json.positions[n][a]), negative[n][a]) << n << " " << a;
        }
    }

    const ParticleSet csv = readParticles(write("zero.csv", "x,y,z,turned,whole\n-0,0,0,-0,-0\n0,-0,-0,0.5,0\n"));
    ASSERT_EQ(csv.size(), 2u);
    EXPECT_TRUE(std::signbit(csv.positions[0][0]));
    EXPECT_FALSE(std::signbit(csv.positions[0][1]));
    EXPECT_TRUE(std::signbit(csv.positions[1][1]));
    const ParticleAttribute& turned = attribute(csv, "turned");
    ASSERT_EQ(turned.type, ScalarType::Float64);
    EXPECT_EQ(turned.asDouble(0), 0.0);
    EXPECT_TRUE(std::signbit(turned.asDouble(0)));
    EXPECT_EQ(turned.asDouble(1), 0.5);
    const ParticleAttribute& whole = attribute(csv, "whole");
    ASSERT_EQ(whole.type, ScalarType::Int64);
    int64_t values[2];
    std::memcpy(values, whole.bytes.data(), sizeof(values));
    EXPECT_EQ(values[0], 0);
    EXPECT_EQ(values[1], 0);
}

// ---------------------------------------------------------------------------------------
// VDB points

TEST_F(ReadFormatsTest, VdbPointDataGridWithAttributes)
{
    openvdb::initialize();
    const ParticleSet source = readParticles(dataPath("free_particles_125_particles.vtk"));
    std::vector<openvdb::Vec3R> positions(source.positions.begin(), source.positions.end());
    const std::string file = path("points.vdb");
    nonbloppy_test::writeOpenVdbPoints(file, positions, 0.5);

    const ParticleSet particles = readParticles(file);
    ASSERT_EQ(particles.size(), positions.size());
    const ParticleAttribute& t = attribute(particles, "temperature");
    EXPECT_EQ(t.type, ScalarType::Float32);
    // Points come back in voxel order; the temperature tells which particle each one is.
    for (size_t n = 0; n < particles.size(); ++n) {
        const size_t i = size_t(t.asDouble(n) * 2.0);
        ASSERT_LT(i, positions.size());
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(particles.positions[n][a], positions[i][a], 1e-5);
    }
}

TEST_F(ReadFormatsTest, VdbQuaternionsMatricesAndSplitVectorsAreAttributesOfTheirComponents)
{
    // Quaternions and matrices were skipped without a word. Scalars c_0..c_3 of another
    // program's stay four (only those writeParticles() split and lists are joined again).
    openvdb::initialize();
    const std::vector<openvdb::Vec3R> positions{{0.0, 0.0, 0.0}, {1.0, 2.0, 3.0}};
    const std::string file = path("extras.vdb");
    nonbloppy_test::writeOpenVdbPoints(file, positions, 0.5, nonbloppy_test::PointExtras::QuatMatricesAndSplitVector);
    const ParticleSet particles = readParticles(file);
    ASSERT_EQ(particles.size(), 2u);
    std::vector<std::string> names;
    for (const ParticleAttribute& a : particles.attributes) names.push_back(a.name + "/" + std::to_string(a.components));
    EXPECT_EQ(names, (std::vector<std::string>{"temperature/1", "orient/4", "xform/16", "stress/9", "c_0/1", "c_1/1",
                                               "c_2/1", "c_3/1"}));
    for (size_t n = 0; n < particles.size(); ++n) {
        for (int c = 0; c < 4; ++c) EXPECT_EQ(attribute(particles, "orient").asDouble(n, c), double(c + 1));
        for (int c = 0; c < 16; ++c) EXPECT_EQ(attribute(particles, "xform").asDouble(n, c), double(c));
        for (int c = 0; c < 9; ++c) EXPECT_EQ(attribute(particles, "stress").asDouble(n, c), double(c) + 0.5);
        for (int c = 0; c < 4; ++c) EXPECT_EQ(attribute(particles, "c_" + std::to_string(c)).asDouble(n), double(10 + c));
    }
    EXPECT_EQ(attribute(particles, "stress").type, ScalarType::Float64);
    EXPECT_EQ(attribute(particles, "xform").type, ScalarType::Float32);
}

TEST_F(ReadFormatsTest, PlyDataPastTheDeclaredVerticesIsAnErrorAndOtherElementsAreNamed)
{
    // A row more than the header counts was dropped silently (bug hunt); CSV, XYZ and VTK
    // refuse theirs. Trailing line breaks are no data.
    const std::string header = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                               "property float z\nend_header\n";
    const std::string extra = write("extra.ply", header + "0 0 0\n1 1 1\n2 2 2\n");
    EXPECT_EQ(nonbloppy_test::messageOf<FileError>([&] { readParticles(extra); }),
              "PLY file has 6 bytes more than its header declares (element vertex 2) (" + extra + ")");
    EXPECT_EQ(readParticles(write("ends.ply", header + "0 0 0\n1 1 1\n\n \n")).size(), 2u);
    const float values[6] = {0, 0, 0, 1, 1, 1};
    const std::string binary = "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n"
                               "property float y\nproperty float z\nend_header\n"
                               + std::string(reinterpret_cast<const char*>(values), sizeof(values));
    const std::string junk = write("junk.ply", binary + "JUNK");
    EXPECT_EQ(nonbloppy_test::messageOf<FileError>([&] { readParticles(junk); }),
              "PLY file has 4 bytes more than its header declares (element vertex 2) (" + junk + ")");
    EXPECT_EQ(readParticles(write("newline.ply", binary + "\n")).size(), 2u);
    // MeshLab's point clouds declare "element face 0" after the vertices (review).
    const std::string noFaces = write("nofaces.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
        "property float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0\n1 1 1\n2 2 2\n");
    EXPECT_EQ(nonbloppy_test::messageOf<FileError>([&] { readParticles(noFaces); }),
              "PLY file has 6 bytes more than its header declares (element vertex 2) (" + noFaces + ")");
    // A mesh's faces are not read, but named (convert warned of nothing).
    const ParticleSet mesh = readParticles(write("mesh.ply", "ply\nformat ascii 1.0\nelement vertex 3\n"
        "property float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
        "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
    EXPECT_EQ(mesh.size(), 3u);
    EXPECT_EQ(mesh.skipped, std::vector<std::string>{"element 'face'"});
}

TEST_F(ReadFormatsTest, AVtkMeshsPolygonsAreNamedAsNotReadAndAnEmptySectionIsNot)
{
    const ParticleSet mesh = readParticles(write("mesh.vtk", "# vtk DataFile Version 3.0\nm\nASCII\nDATASET POLYDATA\n"
        "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 2\n"));
    EXPECT_EQ(mesh.skipped, std::vector<std::string>{"POLYGONS section"});
    // VTK 5 counts offsets, one more than the polygons: "POLYGONS 1 0" holds none (review).
    const ParticleSet empty = readParticles(write("empty.vtk", "# vtk DataFile Version 5.1\nm\nASCII\n"
        "DATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 0\nOFFSETS vtktypeint64\n0\n"
        "CONNECTIVITY vtktypeint64\n\n"));
    EXPECT_EQ(empty.size(), 3u);
    EXPECT_TRUE(empty.skipped.empty());
    const ParticleSet one = readParticles(write("one.vtk", "# vtk DataFile Version 5.1\nm\nASCII\n"
        "DATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 2 3\nOFFSETS vtktypeint64\n0 3\n"
        "CONNECTIVITY vtktypeint64\n0 1 2\n"));
    EXPECT_EQ(one.skipped, std::vector<std::string>{"POLYGONS section"});
}

TEST_F(ReadFormatsTest, TwoRunsOfTheSameBaseGiveOneVectorAndScalars)
{
    // v_x v_y v_z and v_0 v_1 became two attributes 'v' (PLY), of which mesh --attributes
    // kept one; CSV refused the file ("duplicate column 'v"). The first run keeps the name.
    const ParticleSet ply = readParticles(write("runs.ply", "ply\nformat ascii 1.0\nelement vertex 1\n"
        "property float x\nproperty float y\nproperty float z\nproperty float v_x\nproperty float v_y\n"
        "property float v_z\nproperty float v_0\nproperty float v_1\nend_header\n0 0 0 1 2 3 4 5\n"));
    std::vector<std::string> names;
    for (const ParticleAttribute& a : ply.attributes) names.push_back(a.name + "/" + std::to_string(a.components));
    EXPECT_EQ(names, (std::vector<std::string>{"v/3", "v_0/1", "v_1/1"}));
    EXPECT_EQ(attribute(ply, "v_1").asDouble(0), 5.0);

    const ParticleSet csv = readParticles(write("runs.csv", "x,y,z,v:0,v:1,v:2,v_x,v_y,v_z\n0,0,0,1,2,3,4,5,6\n"));
    names.clear();
    for (const ParticleAttribute& a : csv.attributes) names.push_back(a.name + "/" + std::to_string(a.components));
    EXPECT_EQ(names, (std::vector<std::string>{"v/3", "v_x/1", "v_y/1", "v_z/1"}));
    EXPECT_EQ(attribute(csv, "v_z").asDouble(0), 6.0);
}

TEST_F(ReadFormatsTest, WholeFloatsStayFloatsThroughCsv)
{
    // A float 300 went out as "300" and came back as an integer attribute, which mesh
    // --attributes carries as the nearest particle's value instead of a mean (bug hunt).
    ParticleSet particles;
    particles.positions = {openvdb::Vec3f(0.0f), openvdb::Vec3f(1.0f, 2.0f, 3.0f)};
    particles.attributes.push_back(ParticleAttribute::of("temperature", 1, std::vector<float>{300.0f, 301.0f}));
    particles.attributes.push_back(ParticleAttribute::of("level", 1, std::vector<double>{-0.0, 1e22}));
    particles.attributes.push_back(ParticleAttribute::of("id", 1, std::vector<int32_t>{7, 8}));
    nonbloppy::writeParticles(particles, path("whole.csv"));
    EXPECT_EQ(readBytes(path("whole.csv")), "x,y,z,temperature,level,id\n0,0,0,300.0,-0.0,7\n1,2,3,301.0,1e+22,8\n");
    const ParticleSet back = readParticles(path("whole.csv"));
    EXPECT_FALSE(nonbloppy::isIntegerType(attribute(back, "temperature").type));
    EXPECT_EQ(attribute(back, "temperature").asDouble(1), 301.0);
    EXPECT_FALSE(nonbloppy::isIntegerType(attribute(back, "level").type));
    EXPECT_EQ(attribute(back, "level").asDouble(1), 1e22);
    EXPECT_TRUE(nonbloppy::isIntegerType(attribute(back, "id").type));
}

TEST_F(ReadFormatsTest, ScalarsNamedLikeComponentsStayScalarsInCsvAndVdb)
{
    // a_0, a_1 of their own came back from .vdb and .csv as one 2-component "a", and a
    // table's p_1 was taken for a position (review). PLY's convention (name_0, name_1 is a
    // vector) is unchanged.
    ParticleSet particles;
    particles.positions = {openvdb::Vec3f(0.0f), openvdb::Vec3f(1.0f, 2.0f, 3.0f)};
    for (const char* name : {"a_0", "a_1", "p_1"}) {
        particles.attributes.push_back(ParticleAttribute::of(name, 1, std::vector<int32_t>{7, 8}));
    }
    for (const std::string ext : {".csv", ".vdb"}) {
        nonbloppy::writeParticles(particles, path("scalars" + ext));
        const ParticleSet back = readParticles(path("scalars" + ext));
        std::vector<std::string> names;
        for (const ParticleAttribute& a : back.attributes) names.push_back(a.name + "/" + std::to_string(a.components));
        EXPECT_EQ(names, (std::vector<std::string>{"a_0/1", "a_1/1", "p_1/1"})) << ext;
        EXPECT_EQ(back.positions[1], openvdb::Vec3f(1.0f, 2.0f, 3.0f)) << ext;
    }
}

TEST_F(ReadFormatsTest, ScalarsNamedLikeOneVectorsColumnsAreWrittenApart)
{
    // Scalars n_x, n_y, n_z came back from PLY and CSV as one vector "n", b_0, b_1 from PLY
    // as "b", and c:0, c:1 from CSV as "c", without a word (format round-trip hunt): the
    // readers join such runs, which is how vectors are written. The scalar that would
    // continue a run gets _2, as a renamed name does, and comes back as written.
    ParticleSet particles;
    particles.positions = {openvdb::Vec3f(0.0f), openvdb::Vec3f(1.0f, 2.0f, 3.0f)};
    for (const char* name : {"n_x", "n_y", "n_z", "b_0", "b_1", "c:0", "c:1", "d_y"}) {
        particles.attributes.push_back(ParticleAttribute::of(name, 1, std::vector<float>{1.5f, 2.5f}));
    }
    const std::vector<std::string> expected[2] = {
        {"n_x", "n_y_2", "n_z", "b_0", "b_1_2", "c:0", "c:1", "d_y"},     // PLY
        {"n_x", "n_y_2", "n_z", "b_0", "b_1", "c:0", "c:1_2", "d_y"}};    // CSV
    int k = 0;
    for (const std::string ext : {".ply", ".csv"}) {
        const std::string file = path("apart" + ext);
        EXPECT_EQ(nonbloppy::writtenAttributeNames(particles, file), expected[k]) << ext;
        nonbloppy::writeParticles(particles, file);
        const ParticleSet back = readParticles(file);
        std::vector<std::string> names;
        for (const ParticleAttribute& a : back.attributes) {
            EXPECT_EQ(a.components, 1) << ext << " " << a.name;
            EXPECT_EQ(a.asDouble(1), 2.5) << ext << " " << a.name;
            names.push_back(a.name);
        }
        EXPECT_EQ(names, expected[k]) << ext;
        ++k;
    }
}

TEST_F(ReadFormatsTest, AScalarNamedAsAVectorsNextComponentStaysItsOwn)
{
    // "a" of 2 components went to PLY and .vdb as a_0, a_1 (CSV a:0, a:1) and a scalar "a_2"
    // beside it read back as a third component: one attribute gone (second bug hunt).
    const auto attributeOf = [](const std::string& name, int components, float first) {
        std::vector<float> values;
        for (int k = 0; k < 2 * components; ++k) values.push_back(first + float(k));
        return ParticleAttribute::of(name, components, values);
    };
    for (const bool scalarFirst : {false, true}) {
        ParticleSet particles;
        particles.positions = {openvdb::Vec3f(0.0f), openvdb::Vec3f(1.0f, 2.0f, 3.0f)};
        particles.attributes = {attributeOf("a", 2, 10.0f), attributeOf("a_2", 1, 20.0f)};
        if (scalarFirst) std::swap(particles.attributes[0], particles.attributes[1]);
        for (const std::string ext : {".ply", ".csv", ".vdb"}) {
            const std::string file = path("next" + ext);
            nonbloppy::writeParticles(particles, file);
            const std::vector<std::string> written = nonbloppy::writtenAttributeNames(particles, file);
            const ParticleSet back = readParticles(file);
            ASSERT_EQ(back.attributes.size(), 2u) << ext << " " << scalarFirst;
            for (size_t i = 0; i < 2; ++i) {
                const ParticleAttribute& a = attribute(back, written[i]);
                EXPECT_EQ(a.components, particles.attributes[i].components) << ext << " " << written[i];
                EXPECT_EQ(a.asDouble(1, a.components - 1), particles.attributes[i].asDouble(1, a.components - 1))
                    << ext << " " << written[i];
            }
        }
    }
}

TEST_F(ReadFormatsTest, WhatNoAttributeCanTakeIsListedAsSkipped)
{
    // A .vdb's groups and a PLY vertex's list properties were left out without a word.
    openvdb::initialize();
    const std::vector<openvdb::Vec3R> positions{{0.0, 0.0, 0.0}, {1.0, 2.0, 3.0}};
    const std::string vdb = path("grouped.vdb");
    nonbloppy_test::writeOpenVdbPoints(vdb, positions, 0.5, nonbloppy_test::PointExtras::IdPairAndGroup);
    const ParticleSet grouped = readParticles(vdb);
    EXPECT_EQ(grouped.skipped, std::vector<std::string>{"group 'tagged'"});
    EXPECT_NE(grouped.findAttribute("id"), nullptr);
    EXPECT_EQ(grouped.findAttribute("__group0"), nullptr);

    const std::string ply = write("listed.ply", "ply\nformat ascii 1.0\nelement vertex 1\n"
                                                "property float x\nproperty float y\nproperty float z\n"
                                                "property list uchar int ids\nproperty float w\nend_header\n"
                                                "1 2 3 2 7 8 0.5\n");
    const ParticleSet listed = readParticles(ply);
    EXPECT_EQ(listed.skipped, std::vector<std::string>{"list property 'ids'"});
    EXPECT_EQ(attribute(listed, "w").asDouble(0), 0.5);
    EXPECT_TRUE(readParticles(dataPath("cube_8_particles.vtk")).skipped.empty());

    // A VTU string array (names, labels) made the whole file unreadable.
    const std::string vtu = write("labelled.vtu",
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\">\n<UnstructuredGrid>\n"
        "<Piece NumberOfPoints=\"2\" NumberOfCells=\"0\">\n<Points>\n"
        "<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 2 3</DataArray>\n</Points>\n"
        "<PointData>\n<DataArray type=\"String\" Name=\"label\" format=\"ascii\">97 0 98 0</DataArray>\n"
        "<DataArray type=\"Float32\" Name=\"w\" format=\"ascii\">0.5 1.5</DataArray>\n</PointData>\n"
        "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    const ParticleSet labelled = readParticles(vtu);
    EXPECT_EQ(labelled.skipped, std::vector<std::string>{"string array 'label'"});
    ASSERT_EQ(labelled.attributes.size(), 1u);
    EXPECT_EQ(attribute(labelled, "w").asDouble(1), 1.5);
}

TEST_F(ReadFormatsTest, ComponentsPastTheThirdRoundTripThroughEveryFormat)
{
    // A 4-component attribute went to CSV as q:0..q:3 and came back as a 3-vector plus a
    // scalar "q:3"; to .vdb as q_0..q_3 and came back as four scalars (bug hunt). Past
    // component 99 the PLY, CSV and .vdb readers split the columns off as scalars.
    ParticleSet particles;
    particles.positions = {openvdb::Vec3f(0.0f), openvdb::Vec3f(1.0f, 2.0f, 3.0f)};
    const std::vector<int> componentCounts = {4, 9, 16, 150};
    for (const int components : componentCounts) {
        std::vector<float> floats;
        std::vector<int32_t> ints;
        for (int k = 0; k < 2 * components; ++k) {
            floats.push_back(float(k) + 0.25f);
            ints.push_back(k - 7);
        }
        const std::string name = "q" + std::to_string(components);
        particles.attributes.push_back(components == 9 ? ParticleAttribute::of(name, components, ints)
                                                       : ParticleAttribute::of(name, components, floats));
    }
    for (const std::string ext : {".csv", ".vdb", ".ply", ".vtk", ".vtu"}) {
        const std::string file = path("round" + ext);
        nonbloppy::writeParticles(particles, file);
        const ParticleSet back = readParticles(file);
        ASSERT_EQ(back.size(), 2u) << ext;
        ASSERT_EQ(back.attributes.size(), componentCounts.size()) << ext;
        // Points of a .vdb come back in voxel order: the origin first here either way.
        for (size_t i = 0; i < componentCounts.size(); ++i) {
            const ParticleAttribute& written = particles.attributes[i];
            const ParticleAttribute& read = back.attributes[i];
            EXPECT_EQ(read.name, written.name) << ext;
            ASSERT_EQ(read.components, written.components) << ext << " " << written.name;
            for (size_t n = 0; n < 2; ++n) {
                for (int c = 0; c < written.components; ++c) {
                    ASSERT_EQ(read.asDouble(n, c), written.asDouble(n, c)) << ext << " " << written.name;
                }
            }
        }
    }
}

TEST_F(ReadFormatsTest, WhatTheWritersWriteTheirReadersRead)
{
    // Bug hunt: an attribute named "metadata" made a .vtk FIELD line that reads as VTK's
    // METADATA block; 65 components made a .vtu the reader refused (it allowed 64, legacy
    // VTK 4096); one particle 5e9 out got a .vdb voxel of 1, past 32-bit voxel coordinates.
    ParticleSet particles;
    particles.positions = {openvdb::Vec3f(0.0f), openvdb::Vec3f(1.0f, 2.0f, 3.0f)};
    particles.attributes.push_back(ParticleAttribute::of("Metadata", 1, std::vector<float>{1.5f, 2.5f}));
    std::vector<float> wide(2 * 65);
    for (size_t k = 0; k < wide.size(); ++k) wide[k] = float(k);
    particles.attributes.push_back(ParticleAttribute::of("wide", 65, wide));
    const std::string vtk = path("md.vtk");
    nonbloppy::writeParticles(particles, vtk);
    EXPECT_EQ(nonbloppy::writtenAttributeNames(particles, vtk)[0], "Metadata_2");
    const ParticleSet fromVtk = readParticles(vtk);
    ASSERT_EQ(fromVtk.attributes.size(), 2u);
    EXPECT_EQ(fromVtk.attributes[0].name, "Metadata_2");
    EXPECT_EQ(fromVtk.attributes[0].asDouble(1), 2.5);
    const std::string vtu = path("wide.vtu");
    nonbloppy::writeParticles(particles, vtu);
    const ParticleSet fromVtu = readParticles(vtu);
    ASSERT_EQ(fromVtu.attributes.size(), 2u);
    EXPECT_EQ(fromVtu.attributes[1].components, 65);
    EXPECT_EQ(fromVtu.attributes[1].asDouble(1, 64), 129.0);
    // Past the 4096 components the readers take, the writers refuse (but .xyz, which
    // stores no attributes).
    ParticleSet wider = particles;
    wider.attributes[1] = ParticleAttribute::of("wider", 4097, std::vector<float>(2 * 4097, 1.0f));
    for (const std::string ext : {".csv", ".ply", ".vdb", ".vtk", ".vtu"}) {
        const std::string file = path("wider" + ext);
        EXPECT_EQ(nonbloppy_test::messageOf<nonbloppy::ParameterError>([&] { nonbloppy::writeParticles(wider, file); }),
                  "attribute 'wider' has 4097 components, more than the 4096 a file holds (" + file + ")");
    }
    nonbloppy::writeParticles(wider, path("wider.xyz"));
    EXPECT_EQ(readParticles(path("wider.xyz")).size(), 2u);

    // A .vtp's polygons are listed as not read, as a legacy VTK's are (bug hunt).
    const std::string vtp = write("tri.vtp",
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\">\n<PolyData>\n"
        "<Piece NumberOfPoints=\"3\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"1\">\n"
        "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 0 1 0</DataArray></Points>\n"
        "<Polys><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2</DataArray>\n"
        "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">3</DataArray></Polys>\n"
        "</Piece>\n</PolyData>\n</VTKFile>\n");
    const ParticleSet triangle = readParticles(vtp);
    EXPECT_EQ(triangle.size(), 3u);
    EXPECT_EQ(triangle.skipped, std::vector<std::string>{"Polys section"});

    ParticleSet far;
    far.positions = {openvdb::Vec3f(5.0e9f, 0.0f, 0.0f)};
    const std::string vdb = path("far.vdb");
    nonbloppy::writeParticles(far, vdb);
    const ParticleSet back = readParticles(vdb);
    ASSERT_EQ(back.size(), 1u);
    EXPECT_NEAR(back.positions[0][0], 5.0e9f, 5.0e9f * 1e-6f);
}

TEST_F(ReadFormatsTest, AVdbsPointGridsAfterTheFirstAreListedAsNotRead)
{
    // Only the first PointDataGrid is read; a second one's particles were left out of the
    // mesh without a word (bug hunt).
    ParticleSet a, b;
    a.positions = {openvdb::Vec3f(0.0f), openvdb::Vec3f(1.0f, 0.0f, 0.0f)};
    b.positions = {openvdb::Vec3f(5.0f), openvdb::Vec3f(6.0f), openvdb::Vec3f(7.0f)};
    openvdb::GridBase::Ptr first = nonbloppy::makePointDataGrid(a), second = nonbloppy::makePointDataGrid(b);
    first->setName("A");
    second->setName("B");
    const std::string vdb = path("two.vdb");
    nonbloppy::writeVdb({first, second}, vdb);
    const ParticleSet read = readParticles(vdb);
    EXPECT_EQ(read.size(), 2u);
    EXPECT_EQ(read.skipped, std::vector<std::string>{"point grid 'B'"});
}

TEST_F(ReadFormatsTest, VdbWithoutPointsIsAClearError)
{
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create();
    density->setName("density");
    density->tree().setValue(openvdb::Coord(1, 2, 3), 1.0f);
    const std::string file = path("density.vdb");
    openvdb::io::File(file).write({density});
    EXPECT_EQ(fileErrorOf(file), "no PointDataGrid in this .vdb file (grids: density float); a density "
                                 "cache holds no particles to read (" + file + ")");
    const std::string junk = write("junk.vdb", "not a vdb file at all");
    EXPECT_EQ(fileErrorOf(junk).rfind("cannot read .vdb file: ", 0), 0u) << fileErrorOf(junk);
}

TEST_F(ReadFormatsTest, VdbAttributesKeepTheSignOfZero)
{
    // OpenVDB's populateAttribute() collapses a leaf's array to its first value when all
    // values compare equal (==), as 0.0 and -0.0 do: the zeros came back with the first
    // one's sign (format round-trip hunt).
    ParticleSet particles;
    particles.positions = {openvdb::Vec3f(0.0f), openvdb::Vec3f(0.25f, 0.0f, 0.0f)};  // one leaf
    particles.attributes.push_back(ParticleAttribute::of("f", 1, std::vector<float>{0.0f, -0.0f}));
    particles.attributes.push_back(ParticleAttribute::of("d", 1, std::vector<double>{-0.0, 0.0}));
    particles.attributes.push_back(ParticleAttribute::of("negative", 1, std::vector<double>{-0.0, -0.0}));
    particles.attributes.push_back(ParticleAttribute::of("v", 3, std::vector<float>{0.0f, -0.0f, 0.0f, -0.0f, 0.0f, -0.0f}));
    particles.attributes.push_back(ParticleAttribute::of("q", 4, std::vector<float>{-0.0f, 0.0f, 0.0f, 0.0f,
                                                                                     0.0f, 0.0f, 0.0f, -0.0f}));
    const std::string file = path("zeros.vdb");
    nonbloppy::writeParticles(particles, file);
    const ParticleSet back = readParticles(file);
    ASSERT_EQ(back.size(), 2u);
    ASSERT_EQ(back.attributes.size(), particles.attributes.size());
    for (size_t n = 0; n < 2; ++n) {
        const size_t original = back.positions[n][0] > 0.1f ? 1 : 0;  // a .vdb may reorder them
        for (size_t i = 0; i < particles.attributes.size(); ++i) {
            const ParticleAttribute& written = particles.attributes[i];
            const ParticleAttribute& read = back.attributes[i];
            ASSERT_EQ(read.name, written.name);
            ASSERT_EQ(read.type, written.type) << read.name;
            ASSERT_EQ(read.components, written.components) << read.name;
            const size_t bytes = size_t(written.components) * nonbloppy::scalarSize(written.type);
            EXPECT_EQ(std::memcmp(read.bytes.data() + n * bytes, written.bytes.data() + original * bytes, bytes), 0)
                << read.name << " of particle " << original;
        }
    }
}

TEST_F(ReadFormatsTest, AnEmptyVdbKeepsItsAttributes)
{
    // With no particles OpenVDB makes no leaf, and the attributes, which only the leaves
    // describe, were gone without a word (format round-trip hunt).
    ParticleSet empty;
    empty.attributes.push_back(ParticleAttribute::of("temperature", 1, std::vector<float>{}));
    empty.attributes.push_back(ParticleAttribute::of("v", 3, std::vector<double>{}));
    empty.attributes.push_back(ParticleAttribute::of("id", 1, std::vector<int64_t>{}));
    empty.attributes.push_back(ParticleAttribute::of("q", 4, std::vector<float>{}));
    empty.attributes.push_back(ParticleAttribute::of("flag", 1, std::vector<int8_t>{}));
    const std::string file = path("empty.vdb");
    nonbloppy::writeParticles(empty, file);
    const ParticleSet back = readParticles(file);
    EXPECT_EQ(back.size(), 0u);
    EXPECT_TRUE(back.skipped.empty());
    expectSameParticles(back, empty);
    // As makePointDataGrid() gives it to a caller too.
    openvdb::GridBase::Ptr grid = nonbloppy::makePointDataGrid(empty);
    nonbloppy::writeVdb({grid}, path("grid.vdb"));
    expectSameParticles(readParticles(path("grid.vdb")), empty);
}

} // namespace

namespace {

TEST_F(ReadFormatsTest, TextNumbersReadTheSameUnderACommaDecimalLocale)
{
    // Values past double's range went through std::strtod, which follows the process's
    // locale: a host application that called setlocale() for German read 1.5e-400 as 1
    // (CSV, VTU) or refused it (ASCII PLY) (API review). The locale is built here, as a
    // host's would be installed; tools/setup.sh installs the definitions (package locales).
    const std::string localeDir = path("locales");
    ASSERT_EQ(::mkdir(localeDir.c_str(), 0700), 0);
    ASSERT_EQ(std::system(("localedef -i de_DE -f UTF-8 " + localeDir + "/de_DE.UTF-8 2>/dev/null").c_str()), 0)
        << "localedef needs the Debian package locales";
    ASSERT_EQ(::setenv("LOCPATH", localeDir.c_str(), 1), 0);
    ASSERT_NE(std::setlocale(LC_ALL, "de_DE.UTF-8"), nullptr);
    ASSERT_EQ(std::string(std::localeconv()->decimal_point), ",");
    struct RestoreLocale
    {
        ~RestoreLocale()
        {
            std::setlocale(LC_ALL, "C");
            ::unsetenv("LOCPATH");
        }
    } restore;

    const double denormal = std::numeric_limits<double>::denorm_min();  // 4.9e-324
    const auto expectValues = [&](const ParticleSet& particles, const std::string& what) {
        ASSERT_EQ(particles.size(), 3u) << what;
        const ParticleAttribute& c = attribute(particles, "c");
        EXPECT_EQ(c.asDouble(0), 0.0) << what;
        EXPECT_EQ(c.asDouble(1), denormal) << what;
        EXPECT_EQ(c.asDouble(2), 2.5) << what;
    };
    const char* values[3] = {"1.5e-400", "4.9406564584124654e-324", "2.5"};
    std::string csv = "x,y,z,c\n", ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
        "property float y\nproperty float z\nproperty double c\nend_header\n", vtuValues;
    for (int n = 0; n < 3; ++n) {
        csv += std::to_string(n) + ",0,0," + values[n] + "\n";
        ply += std::to_string(n) + " 0 0 " + values[n] + "\n";
        vtuValues += std::string(" ") + values[n];
    }
    expectValues(readParticles(write("c.csv", csv)), "CSV");
    expectValues(readParticles(write("c.ply", ply)), "ASCII PLY");
    expectValues(readParticles(write("c.vtu",
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
        "<UnstructuredGrid>\n<Piece NumberOfPoints=\"3\" NumberOfCells=\"0\">\n"
        "<PointData><DataArray type=\"Float64\" Name=\"c\" format=\"ascii\">" + vtuValues + "</DataArray></PointData>\n"
        "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 2 0 0</DataArray></Points>\n"
        "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")), "VTU");
}

} // namespace

TEST_F(ReadFormatsTest, VdbPositionsComeBackBitForBit)
{
    // OpenVDB keeps a position as its voxel plus a float offset within it, scaled back by the
    // voxel size. The size points::computeVoxelSize() picks (1.7457, say) rounded both ways,
    // and some positions came back a float step off (0.45 as 0.44999996; format round-trip
    // hunt); a power of two splits and scales exactly. A real frame, and floats of many
    // magnitudes with a fixed seed.
    ParticleSet particles = readParticles(dataPath("dam_break_frame_23_24389_particles.vtk"));
    particles.attributes.clear();
    std::mt19937 random(12345);
    std::uniform_real_distribution<float> mantissa(-1.0f, 1.0f);
    std::uniform_int_distribution<int> exponent(-12, 12);
    for (int n = 0; n < 20000; ++n) {
        openvdb::Vec3f p;
        for (int k = 0; k < 3; ++k) p[k] = std::ldexp(mantissa(random), exponent(random));
        particles.positions.push_back(p);
    }
    particles.positions.push_back(openvdb::Vec3f(0.45f, 0.1f, -0.3f));
    const std::string file = path("exact.vdb");
    nonbloppy::writeParticles(particles, file);

    openvdb::io::File vdb(file);
    vdb.open();
    const double voxelSize = vdb.readGrid("points")->voxelSize()[0];
    vdb.close();
    EXPECT_EQ(voxelSize, std::exp2(std::round(std::log2(voxelSize)))) << "not a power of two";

    // A .vdb lists the points leaf by leaf: compare the positions as sorted bit patterns.
    const auto sortedBits = [](const std::vector<openvdb::Vec3f>& positions) {
        std::vector<std::array<uint32_t, 3>> bits(positions.size());
        for (size_t n = 0; n < positions.size(); ++n) std::memcpy(bits[n].data(), positions[n].asPointer(), 12);
        std::sort(bits.begin(), bits.end());
        return bits;
    };
    const ParticleSet back = readParticles(file);
    ASSERT_EQ(back.size(), particles.size());
    const auto written = sortedBits(particles.positions), read = sortedBits(back.positions);
    size_t differing = 0;
    for (size_t n = 0; n < written.size(); ++n) differing += written[n] != read[n];
    EXPECT_EQ(differing, 0u) << "of " << written.size() << " positions";
}

TEST_F(ReadFormatsTest, VdbPointsReadTheSameInTreeOrderWhateverTheThreadCount)
{
    // The leaves are converted in parallel, each into its place: the particles and their
    // attributes must come out in the grid's leaf order, the same bytes at one thread and at
    // four. A real frame at a voxel size that gives it hundreds of leaves.
    openvdb::initialize();
    const ParticleSet frame = readParticles(dataPath("dam_break_frame_23_24389_particles.vtk"));
    const std::vector<openvdb::Vec3R> positions(frame.positions.begin(), frame.positions.end());
    const std::string file = path("frame.vdb");
    nonbloppy_test::writeOpenVdbPoints(file, positions, 0.02);
    const auto readWith = [&](int threads) {
        tbb::task_arena arena(threads);
        return arena.execute([&] { return readParticles(file); });
    };
    const ParticleSet one = readWith(1), four = readWith(4);
    ASSERT_EQ(one.size(), positions.size());
    ASSERT_EQ(four.size(), positions.size());
    EXPECT_EQ(std::memcmp(one.positions.data(), four.positions.data(), one.size() * sizeof(openvdb::Vec3f)), 0);
    EXPECT_TRUE(attribute(one, "temperature").bytes == attribute(four, "temperature").bytes);

    // The order: OpenVDB's own walk of the grid, leaf by leaf, each point at its voxel plus
    // its offset, as the reader computes it (so the same bits).
    openvdb::io::File vdb(file);
    vdb.open();
    const auto grid = openvdb::gridPtrCast<openvdb::points::PointDataGrid>(vdb.readGrid("points"));
    vdb.close();
    ASSERT_TRUE(grid);
    std::vector<openvdb::Vec3f> walked;
    size_t leaves = 0;
    for (auto leaf = grid->tree().cbeginLeaf(); leaf; ++leaf, ++leaves) {
        openvdb::points::AttributeHandle<openvdb::Vec3f> offset(leaf->constAttributeArray("P"));
        for (auto index = leaf->beginIndexAll(); index; ++index) {
            walked.push_back(openvdb::Vec3f(grid->transform().indexToWorld(
                index.getCoord().asVec3d() + openvdb::Vec3d(offset.get(*index)))));
        }
    }
    EXPECT_GT(leaves, 200u) << "too few leaves to test the parallel loop";
    ASSERT_EQ(walked.size(), four.size());
    EXPECT_EQ(std::memcmp(walked.data(), four.positions.data(), walked.size() * sizeof(openvdb::Vec3f)), 0);
    // And each point is the particle its temperature (number / 2) names.
    const ParticleAttribute& temperature = attribute(four, "temperature");
    size_t misplaced = 0;
    for (size_t n = 0; n < four.size(); ++n) {
        const size_t i = size_t(temperature.asDouble(n) * 2.0);
        ASSERT_LT(i, positions.size());
        misplaced += !((four.positions[n] - openvdb::Vec3f(positions[i])).length() < 1e-5f);
    }
    EXPECT_EQ(misplaced, 0u);
}
