// SPDX-License-Identifier: Apache-2.0
// Tests for the streaming BGEO, CSV/TXT and JSON readers (src/StreamReader.h): files larger
// than the reader's 1 MiB buffer, so values, points and lines straddle buffer boundaries;
// BGEO plain and gzip (inflated on the fly); tables with extra columns, CRLF, comments and
// a line longer than the buffer; JSON through the SAX parser; truncation and bad values deep
// inside a file give the messages the whole-file readers gave; hostile counts are rejected.
// Each file is read both by path (readBgeoFile & co.) and through readParticles(); pipes,
// which have no size, are read whole.

#include "TestUtil.h"

#include "../src/ParticleReaders.h"
#include "../src/StreamReader.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/ReadParticles.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <nlohmann/json.hpp>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <sys/stat.h>

namespace {

using nonbloppy::FileError;
using nonbloppy::ParticleAttribute;
using nonbloppy::ParticleSet;
using nonbloppy::ScalarType;
using nonbloppy::readParticles;
namespace io = nonbloppy::io_internal;

using nonbloppy_test::messageOf;
using nonbloppy_test::readBytes;
using nonbloppy_test::writeBytes;

/// Each test in a fresh directory; write() is ScratchDirTest's.
class ReadStreamingFormatsTest : public nonbloppy_test::ScratchDirTest
{
};

/// More particles than fit in a 1 MiB buffer in every layout below.
constexpr size_t kManyParticles = 120001;

/// Particle @a i of a synthetic frame: irregular values.
struct Record
{
    float x, y, z;
    float density;
    int32_t id;
    float velocity[3];
};

Record
record(size_t i)
{
    const float t = float(i);
    return {0.001f * t - 17.25f, std::sin(t) * 3.0f, 1.0f / (1.0f + t), 1000.0f + std::cos(t),
            int32_t(i * 7919 % 100003) - 50000,
            {t * 0.5f, -t * 0.25f, std::sqrt(t)}};
}

std::string
bigEndian32(uint32_t v)
{
    return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
}

std::string
bigEndianFloat(float f)
{
    uint32_t bits;
    std::memcpy(&bits, &f, 4);
    return bigEndian32(bits);
}

std::string
bigEndian16(uint16_t v)
{
    return {char(v >> 8), char(v)};
}

/// A classic BGEO with @a count points (header claims @a claimed, default the same):
/// attributes density (float), id (int), velocity (vector 3), kind (index, 2 strings).
std::string
bgeoBytes(size_t count, int64_t claimed = -1)
{
    std::string b = "BgeoV" + bigEndian32(5) + bigEndian32(uint32_t(claimed < 0 ? int64_t(count) : claimed));
    for (uint32_t v : {1u, 0u, 0u, 4u, 0u, 0u, 0u}) b += bigEndian32(v);  // prims ... attributes
    auto name = [&](const std::string& n) { b += bigEndian16(uint16_t(n.size())) + n; };
    name("density");
    b += bigEndian16(1) + bigEndian32(0) + bigEndianFloat(1000.0f);
    name("id");
    b += bigEndian16(1) + bigEndian32(1) + bigEndian32(0);
    name("velocity");
    b += bigEndian16(3) + bigEndian32(5) + std::string(12, '\0');
    name("kind");
    b += bigEndian16(1) + bigEndian32(4) + bigEndian32(2);
    name("water");
    name("foam");
    for (size_t i = 0; i < count; ++i) {
        const Record r = record(i);
        b += bigEndianFloat(r.x) + bigEndianFloat(r.y) + bigEndianFloat(r.z) + bigEndianFloat(1.0f);
        b += bigEndianFloat(r.density) + bigEndian32(uint32_t(r.id));
        for (float v : r.velocity) b += bigEndianFloat(v);
        b += bigEndian32(uint32_t(i % 2));
    }
    b += "primitives and the rest, ignored";
    return b;
}

/// Bytes of the BGEO attribute table above; the points start at 41 + this.
constexpr size_t kBgeoTableBytes = (2 + 7 + 2 + 4 + 4) + (2 + 2 + 2 + 4 + 4) + (2 + 8 + 2 + 4 + 12)
                                 + (2 + 4 + 2 + 4 + 4 + 2 + 5 + 2 + 4);
constexpr size_t kBgeoPointBytes = 16 + 4 + 4 + 12 + 4;

std::string
gzipBytes(const std::string& plain)
{
    z_stream stream{};
    EXPECT_EQ(deflateInit2(&stream, 6, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY), Z_OK);
    std::string out(deflateBound(&stream, uLong(plain.size())), '\0');
    stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(plain.data()));
    stream.avail_in = uInt(plain.size());
    stream.next_out = reinterpret_cast<Bytef*>(out.data());
    stream.avail_out = uInt(out.size());
    EXPECT_EQ(deflate(&stream, Z_FINISH), Z_STREAM_END);
    out.resize(stream.total_out);
    deflateEnd(&stream);
    return out;
}

using nonbloppy_test::attribute;

void
expectBgeoParticles(const ParticleSet& particles, size_t count)
{
    ASSERT_EQ(particles.size(), count);
    ASSERT_EQ(particles.attributes.size(), 4u);
    const ParticleAttribute& density = attribute(particles, "density");
    const ParticleAttribute& id = attribute(particles, "id");
    const ParticleAttribute& velocity = attribute(particles, "velocity");
    const ParticleAttribute& kind = attribute(particles, "kind");
    EXPECT_EQ(density.type, ScalarType::Float32);
    EXPECT_EQ(id.type, ScalarType::Int32);
    EXPECT_EQ(velocity.components, 3);
    EXPECT_EQ(kind.type, ScalarType::Int32);
    for (size_t i = 0; i < count; ++i) {
        const Record r = record(i);
        ASSERT_EQ(particles.positions[i], openvdb::Vec3f(r.x, r.y, r.z)) << i;
        ASSERT_EQ(density.asDouble(i), double(r.density)) << i;
        ASSERT_EQ(id.asDouble(i), double(r.id)) << i;
        for (int c = 0; c < 3; ++c) ASSERT_EQ(velocity.asDouble(i, c), double(r.velocity[c])) << i;
        ASSERT_EQ(kind.asDouble(i), double(i % 2)) << i;
    }
}

/// The FileError of reading @a path by path, which must equal readParticles()'s.
std::string
errorOfBoth(const std::string& path, const std::function<ParticleSet(const std::string&)>& readFile)
{
    const std::string direct = messageOf<FileError>([&] { readFile(path); });
    EXPECT_EQ(direct, messageOf<FileError>([&] { readParticles(path); })) << path;
    return direct;
}

// ---------------------------------------------------------------------------------------
// BGEO

TEST_F(ReadStreamingFormatsTest, BgeoPlainAndGzipLargerThanTheBuffer)
{
    const std::string plain = bgeoBytes(kManyParticles);
    ASSERT_GT(plain.size(), 4 * io::kChunkBytes);
    const std::string plainFile = write("plain.bgeo", plain);
    expectBgeoParticles(io::readBgeoFile(plainFile), kManyParticles);
    expectBgeoParticles(readParticles(plainFile), kManyParticles);

    const std::string gz = gzipBytes(plain);
    ASSERT_GT(gz.size(), io::kChunkBytes);
    const std::string gzFile = write("gz.bgeo", gz);
    expectBgeoParticles(io::readBgeoFile(gzFile), kManyParticles);
    expectBgeoParticles(readParticles(gzFile), kManyParticles);

    // No points at all, plain and gzip.
    expectBgeoParticles(io::readBgeoFile(write("empty.bgeo", bgeoBytes(0))), 0);
    expectBgeoParticles(io::readBgeoFile(write("emptygz.bgeo", gzipBytes(bgeoBytes(0)))), 0);
}

TEST_F(ReadStreamingFormatsTest, BgeoTruncatedDeepInTheFile)
{
    const std::string plain = bgeoBytes(kManyParticles);
    const size_t pointsStart = 41 + kBgeoTableBytes;
    ASSERT_EQ(plain.substr(pointsStart, 4), bigEndianFloat(record(0).x));
    const size_t left = 3 * io::kChunkBytes + 7;
    const std::string expected = "truncated BGEO points: header claims " + std::to_string(kManyParticles) +
        " points of " + std::to_string(kBgeoPointBytes) + " bytes, " + std::to_string(left) + " bytes left";
    const std::string cut = plain.substr(0, pointsStart + left);
    const std::string cutFile = write("cut.bgeo", cut);
    EXPECT_EQ(errorOfBoth(cutFile, io::readBgeoFile), expected + " (" + cutFile + ")");

    // A complete gzip stream of the cut file: the same message, found while reading.
    const std::string cutGzFile = write("cutgz.bgeo", gzipBytes(cut));
    EXPECT_EQ(errorOfBoth(cutGzFile, io::readBgeoFile), expected + " (" + cutGzFile + ")");

    // The gzip stream itself cut deep inside, or corrupted there.
    const std::string gz = gzipBytes(plain);
    const std::string gzCut = write("gzcut.bgeo", gz.substr(0, gz.size() - gz.size() / 4));
    EXPECT_EQ(errorOfBoth(gzCut, io::readBgeoFile), "truncated gzip data (" + gzCut + ")");
    std::string flipped = gz;
    for (size_t i = gz.size() / 2; i < gz.size() / 2 + 100; ++i) flipped[i] = char(~flipped[i]);
    const std::string corrupt = write("corrupt.bgeo", flipped);
    EXPECT_EQ(errorOfBoth(corrupt, io::readBgeoFile).rfind("corrupt gzip data: ", 0), 0u);

    // gzip errors come before BGEO ones, as when the whole file was inflated first.
    std::string badType = plain;
    badType[41 + 2 + 7 + 2 + 3] = 9;  // density's houdini type 0 -> 9
    const std::string badTypeFile = write("badtype.bgeo", badType);
    EXPECT_EQ(errorOfBoth(badTypeFile, io::readBgeoFile),
              "unsupported BGEO attribute type 9 of 'density' (" + badTypeFile + ")");
    const std::string badTypeGz = gzipBytes(badType);
    const std::string badTypeGzCut = write("badtypegz.bgeo", badTypeGz.substr(0, badTypeGz.size() / 2));
    EXPECT_EQ(errorOfBoth(badTypeGzCut, io::readBgeoFile), "truncated gzip data (" + badTypeGzCut + ")");
}

TEST_F(ReadStreamingFormatsTest, BgeoHostileCountsAreRejected)
{
    // Plain: checked against the file size before allocating.
    const std::string plain = bgeoBytes(3, 1000000000);
    const std::string plainFile = write("hostile.bgeo", plain);
    const size_t left = plain.size() - 41 - kBgeoTableBytes;
    EXPECT_EQ(errorOfBoth(plainFile, io::readBgeoFile),
              "truncated BGEO points: header claims 1000000000 points of 40 bytes, " +
              std::to_string(left) + " bytes left (" + plainFile + ")");
    // gzip: beyond deflate's 1032:1 for the compressed bytes left, so truncated for sure.
    const std::string gzFile = write("hostilegz.bgeo", gzipBytes(plain));
    EXPECT_EQ(errorOfBoth(gzFile, io::readBgeoFile),
              "truncated BGEO points: header claims 1000000000 points of 40 bytes, " +
              std::to_string(left) + " bytes left (" + gzFile + ")");
    // gzip within that limit: found short while reading.
    const std::string nearly = bgeoBytes(kManyParticles, int64_t(kManyParticles) + 1000);
    const std::string nearlyFile = write("nearly.bgeo", gzipBytes(nearly));
    EXPECT_EQ(errorOfBoth(nearlyFile, io::readBgeoFile),
              "truncated BGEO points: header claims " + std::to_string(kManyParticles + 1000) +
              " points of 40 bytes, " + std::to_string(nearly.size() - 41 - kBgeoTableBytes) +
              " bytes left (" + nearlyFile + ")");
}

// ---------------------------------------------------------------------------------------
// CSV / TXT

/// A text form of @a value that reads back exactly.
template<typename T>
std::string
text(T value)
{
    std::ostringstream os;
    os.precision(17);
    os << value;
    return os.str();
}

/// id, x, y, z, velocity:0..2, density and a comment column, with @a eol line ends, a
/// comment and a blank line every 1000 rows.
std::string
tableBytes(size_t count, const std::string& eol, char separator = ',')
{
    const std::string s(1, separator);
    std::string t = "# made by test_ReadStreamingFormats" + eol;
    t += "id" + s + "x" + s + "y" + s + "z" + s + "velocity:0" + s + "velocity:1" + s +
         "velocity:2" + s + "density" + s + "flag" + eol;
    for (size_t i = 0; i < count; ++i) {
        const Record r = record(i);
        t += std::to_string(r.id) + s + text(r.x) + s + text(r.y) + s + text(r.z) + s +
             text(double(r.velocity[0])) + s + text(double(r.velocity[1])) + s +
             text(double(r.velocity[2])) + s + text(double(r.density) + 0.5) + s +
             std::to_string(i % 3) + eol;
        if (i % 1000 == 999) t += "# comment" + eol + eol;
    }
    return t;
}

void
expectTableParticles(const ParticleSet& particles, size_t count)
{
    ASSERT_EQ(particles.size(), count);
    ASSERT_EQ(particles.attributes.size(), 4u);
    const ParticleAttribute& id = attribute(particles, "id");
    const ParticleAttribute& velocity = attribute(particles, "velocity");
    const ParticleAttribute& density = attribute(particles, "density");
    const ParticleAttribute& flag = attribute(particles, "flag");
    EXPECT_EQ(id.type, ScalarType::Int64);
    EXPECT_EQ(flag.type, ScalarType::Int64);
    EXPECT_EQ(velocity.type, ScalarType::Float64);
    EXPECT_EQ(velocity.components, 3);
    EXPECT_EQ(density.type, ScalarType::Float64);
    for (size_t i = 0; i < count; ++i) {
        const Record r = record(i);
        ASSERT_EQ(particles.positions[i], openvdb::Vec3f(r.x, r.y, r.z)) << i;
        ASSERT_EQ(id.asDouble(i), double(r.id)) << i;
        for (int c = 0; c < 3; ++c) ASSERT_EQ(velocity.asDouble(i, c), double(r.velocity[c])) << i;
        ASSERT_EQ(density.asDouble(i), double(r.density) + 0.5) << i;
        ASSERT_EQ(flag.asDouble(i), double(i % 3)) << i;
    }
}

TEST_F(ReadStreamingFormatsTest, TablesLargerThanTheBuffer)
{
    const std::string csv = tableBytes(kManyParticles, "\n");
    ASSERT_GT(csv.size(), 4 * io::kChunkBytes);
    const std::string csvFile = write("p.csv", csv);
    expectTableParticles(io::readTableFile(csvFile), kManyParticles);
    expectTableParticles(readParticles(csvFile), kManyParticles);

    // CRLF, semicolons, no line break after the last row.
    std::string crlf = tableBytes(kManyParticles, "\r\n", ';');
    crlf.resize(crlf.size() - 2);
    expectTableParticles(io::readTableFile(write("crlf.csv", crlf)), kManyParticles);

    // Spaces, and a comment line longer than the buffer in the middle.
    std::string txt = tableBytes(kManyParticles, "\n", ' ');
    const size_t middle = txt.find('\n', txt.size() / 2) + 1;
    txt.insert(middle, "#" + std::string(3 * io::kChunkBytes, 'c') + "\n");
    expectTableParticles(io::readTableFile(write("p.txt", txt)), kManyParticles);
}

TEST_F(ReadStreamingFormatsTest, TableColumnTypesChangeDeepInTheFileAsRowByRow)
{
    // Rows are parsed in parallel, a buffered block at a time, and stored in order: a column
    // of whole numbers turns uint64 at a value past int64 and float64 at a fraction, many
    // blocks in, with every value before it converted ("-0" to -0.0, "+-0" too, as a
    // float parse reads it); another stays int64 to the end. Same at one thread and eight.
    constexpr size_t kRows = 200000, kLarge = 150000, kFraction = 190000, kMinusZero = 170000;
    std::string csv = "x,y,z,n,id\n";
    for (size_t i = 0; i < kRows; ++i) {
        std::string n = std::to_string(i);
        if (i == kLarge) n = "9223372036854775808";
        if (i == kMinusZero) n = "-0";
        if (i == kMinusZero + 1) n = "+-0";
        if (i == kFraction) n = "2.5";
        csv += std::to_string(i % 97) + ".5," + std::to_string(i % 89) + ",-" + std::to_string(i % 83) + "e-1," + n +
               "," + std::to_string(int64_t(i) - 100000) + "\n";
    }
    ASSERT_GT(csv.size(), 4 * io::kChunkBytes);
    const std::string file = write("types.csv", csv);
    ParticleSet one;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = io::readTableFile(file);
    }
    ParticleSet many;
    {
        // Eight threads, whatever the machine has, so that pieces are parsed out of order.
        tbb::global_control wide(tbb::global_control::max_allowed_parallelism, 8);
        tbb::task_arena arena(8);
        arena.execute([&] { many = io::readTableFile(file); });
    }
    for (const ParticleSet* particles : {&std::as_const(one), &std::as_const(many)}) {
        ASSERT_EQ(particles->size(), kRows);
        const ParticleAttribute& n = *particles->findAttribute("n");
        const ParticleAttribute& id = *particles->findAttribute("id");
        ASSERT_EQ(n.type, ScalarType::Float64);
        ASSERT_EQ(id.type, ScalarType::Int64);
        for (size_t i = 0; i < kRows; i += 997) {
            const float z = float(std::stod("-" + std::to_string(i % 83) + "e-1"));
            ASSERT_EQ(particles->positions[i], openvdb::Vec3f(float(i % 97) + 0.5f, float(i % 89), z)) << i;
            ASSERT_EQ(n.asDouble(i), double(i)) << i;
            ASSERT_EQ(id.asDouble(i), double(int64_t(i) - 100000)) << i;
        }
        EXPECT_EQ(n.asDouble(kLarge), 9223372036854775808.0);
        EXPECT_EQ(n.asDouble(kFraction), 2.5);
        EXPECT_TRUE(n.asDouble(kMinusZero) == 0.0 && std::signbit(n.asDouble(kMinusZero)));
        EXPECT_TRUE(n.asDouble(kMinusZero + 1) == 0.0 && std::signbit(n.asDouble(kMinusZero + 1)));
        EXPECT_EQ(n.asDouble(kRows - 1), double(kRows - 1));
    }
    EXPECT_TRUE(one.positions == many.positions);
    EXPECT_TRUE(one.attributes[0].bytes == many.attributes[0].bytes);
    EXPECT_TRUE(one.attributes[1].bytes == many.attributes[1].bytes);
}

TEST_F(ReadStreamingFormatsTest, TableErrorsDeepInTheFile)
{
    const std::string csv = tableBytes(kManyParticles, "\n");
    // Line numbers count every line: the comment, the header, rows and the comment and
    // blank line after every 1000 rows.
    auto lineOfRow = [](size_t row) { return 3 + row + 2 * (row / 1000); };
    const size_t row = kManyParticles * 3 / 4;
    const size_t start = [&] {
        size_t pos = 0;
        for (size_t line = 1; line < lineOfRow(row); ++line) pos = csv.find('\n', pos) + 1;
        return pos;
    }();
    ASSERT_EQ(csv.compare(start, std::to_string(record(row).id).size() + 1, std::to_string(record(row).id) + ","), 0);

    // Cut in the middle of a row: it has fewer fields.
    const std::string cut = write("cut.csv", csv.substr(0, csv.find(',', csv.find(',', start) + 1)));
    EXPECT_EQ(errorOfBoth(cut, io::readTableFile),
              "line " + std::to_string(lineOfRow(row)) + " has 2 fields, the header 9 (" + cut + ")");

    std::string bad = csv;
    bad.replace(start, std::to_string(record(row).id).size(), "12x");
    const std::string badFile = write("bad.csv", bad);
    EXPECT_EQ(errorOfBoth(badFile, io::readTableFile),
              "bad number '12x' on line " + std::to_string(lineOfRow(row)) + " (" + badFile + ")");

    // Two errors pieces apart (a block is cut into pieces of 64 KiB, parsed in any order):
    // the one nearer the start is reported, before or after the bad number.
    const auto withExtraField = [&](std::string text, size_t otherRow) {
        size_t pos = 0;
        for (size_t line = 1; line <= lineOfRow(otherRow); ++line) pos = text.find('\n', pos) + 1;
        text.insert(pos - 1, ",7");  // at the end of the row's line
        return text;
    };
    const std::string laterFile = write("later.csv", withExtraField(bad, row + 3000));
    EXPECT_EQ(errorOfBoth(laterFile, io::readTableFile),
              "bad number '12x' on line " + std::to_string(lineOfRow(row)) + " (" + laterFile + ")");
    const std::string earlierFile = write("earlier.csv", withExtraField(bad, row - 3000));
    EXPECT_EQ(errorOfBoth(earlierFile, io::readTableFile),
              "line " + std::to_string(lineOfRow(row - 3000)) + " has 10 fields, the header 9 (" + earlierFile + ")");
}

// ---------------------------------------------------------------------------------------
// JSON

std::string
jsonBytes(size_t count)
{
    std::string j = "[\n";
    for (size_t i = 0; i < count; ++i) {
        const Record r = record(i);
        j += (i ? ",\n  [" : "  [") + text(r.x) + ", " + text(r.y) + "," + text(r.z) + "]";
    }
    return j + "\n]\n";
}

/// The message the whole-file reader gave for a JSON syntax error in @a bytes.
std::string
jsonSyntaxError(const std::string& bytes)
{
    try {
        const nlohmann::json document = nlohmann::json::parse(bytes);
    } catch (const nlohmann::json::parse_error& e) {
        std::string message = e.what();
        message = message.substr(message.find("] ") + 2);
        return "bad JSON particle list: " + message + " (byte " + std::to_string(e.byte) + ")";
    }
    return "(no parse error)";
}

TEST_F(ReadStreamingFormatsTest, JsonLargerThanTheBuffer)
{
    const std::string json = jsonBytes(kManyParticles);
    ASSERT_GT(json.size(), 4 * io::kChunkBytes);
    const std::string file = write("p.json", json);
    for (const ParticleSet& particles : {io::readJsonFile(file), readParticles(file)}) {
        ASSERT_EQ(particles.size(), kManyParticles);
        EXPECT_TRUE(particles.attributes.empty());
        for (size_t i = 0; i < kManyParticles; ++i) {
            const Record r = record(i);
            ASSERT_EQ(particles.positions[i], openvdb::Vec3f(r.x, r.y, r.z)) << i;
        }
    }
    EXPECT_EQ(io::readJsonFile(write("empty.json", "[]")).size(), 0u);
}

TEST_F(ReadStreamingFormatsTest, JsonErrorsDeepInTheFile)
{
    const std::string json = jsonBytes(kManyParticles);
    const std::string cutBytes = json.substr(0, json.size() * 2 / 3);
    const std::string cut = write("cut.json", cutBytes);
    EXPECT_EQ(errorOfBoth(cut, io::readJsonFile), jsonSyntaxError(cutBytes) + " (" + cut + ")");
    EXPECT_NE(jsonSyntaxError(cutBytes).find("unexpected end of input"), std::string::npos);

    std::string garbled = json;
    const size_t at = json.find('[', json.size() / 2);
    garbled[at + 1] = '@';
    const std::string garbledFile = write("garbled.json", garbled);
    EXPECT_EQ(errorOfBoth(garbledFile, io::readJsonFile), jsonSyntaxError(garbled) + " (" + garbledFile + ")");

    // A point with two coordinates deep inside.
    std::string two = json;
    const size_t point = std::count(json.begin(), json.begin() + long(at), '[') - 1;  // outer '[' too
    const size_t lastComma = json.rfind(',', json.find(']', at));
    two.erase(lastComma, json.find(']', at) - lastComma);
    const std::string twoFile = write("two.json", two);
    EXPECT_EQ(errorOfBoth(twoFile, io::readJsonFile),
              "bad JSON particle list: particle " + std::to_string(point) +
              " has 2 coordinates, expected 3 (" + twoFile + ")");
}

TEST_F(ReadStreamingFormatsTest, JsonNumbersReadWithoutNlohmannAsNlohmannReadsThem)
{
    // `[[x, y, z], ...]` is read without nlohmann; a UTF-8 byte order mark, which nlohmann
    // skips, sends the same text through nlohmann instead. Every number must give the same
    // float bits both ways, and those of strtod's double.
    const std::vector<std::string> numbers = {
        "0", "-0", "1", "-1", "0.1", "-0.0", "1e2", "1E+2", "-2.5e-3", "0.1e1", "16777217", "0.30000000000000004",
        "123456789012345678901234567890", "9007199254740993", "-9223372036854775809", "18446744073709551615",
        "18446744073709551616", "3.4028235677973362e38", "1e-50", "4.9e-324", "2.2250738585072011e-308",
        "-1.00000005960464477539062500001", "123.456e-7", "1e-400", "-1e-400"};
    std::string text = "[";
    const char* spaces[] = {"", " ", "\t", "\r\n", "\n  "};
    for (size_t n = 0; n < numbers.size(); ++n) {
        const std::string space = spaces[n % 5];
        text += (n ? "," : "") + space + "[" + numbers[n] + "," + space + "2" + space + ", " +
                numbers[numbers.size() - 1 - n] + "]" + space;
    }
    text += "]\n";
    const ParticleSet fast = io::readJsonParticles(text.data(), text.size(), "fast.json");
    const std::string bom = "\xef\xbb\xbf" + text;
    const ParticleSet nlohmann = io::readJsonParticles(bom.data(), bom.size(), "bom.json");
    ASSERT_EQ(fast.size(), numbers.size());
    ASSERT_EQ(nlohmann.size(), numbers.size());
    // Float's rounding tie above its largest value goes to infinity: refused both ways, with
    // the same message (it read as an infinite position before).
    for (const std::string prefix : {"", "\xef\xbb\xbf"}) {
        const std::string tie = prefix + "[[0, 0, 0], [1, 3.4028235677973366e38, 2]]";
        EXPECT_EQ(messageOf<FileError>([&] { io::readJsonParticles(tie.data(), tie.size(), "tie.json"); }),
                  "bad JSON particle list: coordinate 3.4028235677973366e+38 of particle 1 lies outside float's "
                  "range (-3.4e38 to 3.4e38) (tie.json)");
    }
    // A number whose double underflows (from_chars refuses it; parseDoubleText() and
    // nlohmann's strtod give +0) is read without nlohmann too.
    const std::string tiny = "[[1e-400, 2, 3]]";
    const ParticleSet tinyParticle = io::readJsonParticles(tiny.data(), tiny.size(), "tiny.json");
    ASSERT_EQ(tinyParticle.size(), 1u);
    EXPECT_EQ(tinyParticle.positions[0], openvdb::Vec3f(0, 2, 3));
    EXPECT_FALSE(std::signbit(tinyParticle.positions[0][0]));
    const auto bits = [](float f) {
        uint32_t b;
        std::memcpy(&b, &f, 4);
        return b;
    };
    for (size_t n = 0; n < numbers.size(); ++n) {
        const float expected = static_cast<float>(std::strtod(numbers[n].c_str(), nullptr));
        EXPECT_EQ(bits(fast.positions[n][0]), bits(expected)) << numbers[n];
        EXPECT_EQ(bits(nlohmann.positions[n][0]), bits(expected)) << numbers[n];
        EXPECT_EQ(bits(fast.positions[n][2]), bits(nlohmann.positions[n][2])) << numbers[numbers.size() - 1 - n];
        EXPECT_EQ(fast.positions[n][1], 2.0f);
    }
}

TEST_F(ReadStreamingFormatsTest, JsonTheFastReadingLeavesToNlohmannReadsTheSame)
{
    // What the fast reading does not take is read again from the start by nlohmann: a
    // particle longer than its 4 KB window is accepted; a number past the largest double,
    // and text JSON forbids, get nlohmann's message, from memory, a file or a pipe.
    const std::string longText = "[[1, 2," + std::string(5000, ' ') + "3], [4, 5, 6]]";
    const ParticleSet longParticle = io::readJsonParticles(longText.data(), longText.size(), "long.json");
    ASSERT_EQ(longParticle.size(), 2u);
    EXPECT_EQ(longParticle.positions[0], openvdb::Vec3f(1, 2, 3));
    EXPECT_EQ(longParticle.positions[1], openvdb::Vec3f(4, 5, 6));
    // A number past the largest double: nlohmann's message.
    const std::string huge = "[[1e400, 2, 3]]";
    EXPECT_EQ(messageOf<FileError>([&] { io::readJsonParticles(huge.data(), huge.size(), "huge.json"); }),
              "bad JSON particle list: number overflow parsing '1e400' (byte 7) (huge.json)");
    for (const std::string bad : {"[[1,2,3]] x", "[[1,2,3],]", "[[01,2,3]]", "[[1.,2,3]]", "[[.5,2,3]]", "[[+1,2,3]]",
                                  "[[1e,2,3]]", "[[-,2,3]]", "[[NaN,2,3]]", "[[1,2,3]", "[[1,2,3]][]", "[[1,2,3] [4,5,6]]"}) {
        const std::string file = write("bad.json", bad);
        EXPECT_EQ(errorOfBoth(file, io::readJsonFile), jsonSyntaxError(bad) + " (" + file + ")") << bad;
        EXPECT_EQ(messageOf<FileError>([&] { io::readJsonParticles(bad.data(), bad.size(), "m.json"); }),
                  jsonSyntaxError(bad) + " (m.json)") << bad;
    }
    // Deep in a pipe, which is loaded whole and read again from memory.
    std::string garbled = jsonBytes(kManyParticles);
    garbled[garbled.find('[', garbled.size() / 2) + 1] = '@';
    const std::string fifo = path("garbled.json");
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    std::thread writer([&] { writeBytes(fifo, garbled); });
    const std::string error = messageOf<FileError>([&] { io::readJsonFile(fifo); });
    writer.join();
    EXPECT_EQ(error, jsonSyntaxError(garbled) + " (" + fifo + ")");
}

// ---------------------------------------------------------------------------------------
// Pipes

TEST_F(ReadStreamingFormatsTest, PipesAreReadWhole)
{
    // A FIFO has no size to check counts against, so it is loaded whole first.
    struct Case { std::string name; std::string bytes; std::function<ParticleSet(const std::string&)> read; };
    const std::vector<Case> cases = {
        {"p.bgeo", gzipBytes(bgeoBytes(kManyParticles)), io::readBgeoFile},
        {"p.csv", tableBytes(kManyParticles, "\n"), io::readTableFile},
        {"p.json", jsonBytes(kManyParticles), io::readJsonFile}};
    for (const Case& c : cases) {
        const std::string fifo = path(c.name);
        ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
        std::thread writer([&] { writeBytes(fifo, c.bytes); });
        ParticleSet particles;
        EXPECT_NO_THROW(particles = c.read(fifo)) << c.name;
        writer.join();
        ASSERT_EQ(particles.size(), kManyParticles) << c.name;
        EXPECT_EQ(particles.positions[kManyParticles - 1],
                  openvdb::Vec3f(record(kManyParticles - 1).x, record(kManyParticles - 1).y,
                                 record(kManyParticles - 1).z)) << c.name;
    }
    expectBgeoParticles(io::readBgeoFile(write("check.bgeo", cases[0].bytes)), kManyParticles);
}

} // namespace
