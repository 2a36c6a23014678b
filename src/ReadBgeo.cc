// SPDX-License-Identifier: Apache-2.0
/// @file ReadBgeo.cc
/// @brief Houdini's classic binary geometry, in the layout Partio and SPlisHSPlasH write:
///
///     "BgeoV" int32 version(5) int32 nPoints nPrims nPointGroups nPrimGroups
///             nPointAttrib nVertexAttrib nPrimAttrib nAttrib
///     per point attribute: uint16 nameLength, name, uint16 size, int32 houdiniType,
///             defaults (size × 4 bytes; type 4 "index" has a string table instead)
///     per point: float32 x y z w, then each attribute's size × 4 bytes
///
/// everything big-endian. Primitives and the rest that follows the points are ignored.
/// Newer Houdini `.bgeo` files are JSON-based (binary JSON starts with byte 0x7f, text
/// JSON with '['); they are reported as unsupported rather than misread, with the name
/// under which Houdini writes the classic layout, `.bhclassic`.
///
/// The file is read through a StreamReader (a bounded buffer, gzip inflated on the fly)
/// and the points are decoded from it straight into the final arrays. An uncompressed
/// file's point count is checked against the bytes left before allocating. A gzip file's
/// inflated size is unknown until its end: a count beyond what deflate's 1032:1 limit
/// allows is truncated for sure (rejected before allocating); a smaller one reserves at
/// most kTrustedRatio times the compressed bytes left, and the arrays grow as points
/// actually arrive beyond that, so a hostile count never allocates more than the data.

#include "Decode.h"
#include "FileFormats.h"
#include "ParticleReaders.h"
#include "StreamReader.h"

#include <nonbloppy/Error.h>

#include <cstring>

namespace nonbloppy {
namespace io_internal {

namespace {

using namespace decode_internal;

/// Arrays are reserved up front for at most this many inflated bytes per compressed byte
/// left; particle floats rarely compress better than 2:1. Beyond it they grow as read.
constexpr uint64_t kTrustedRatio = 8;

/// Points decoded per block of a gzip file (the arrays grow a block at a time).
constexpr size_t kBlockPoints = size_t(1) << 16;

/// Big-endian values from a StreamReader; a short read fails with "truncated <section>".
class BigEndianInput
{
public:
    BigEndianInput(StreamReader& in, const std::string& path) : mIn(in), mPath(path) {}

    void need(size_t bytes, const char* section)
    {
        if (!mIn.ensure(bytes)) fail(mPath, std::string("truncated ") + section);
    }
    uint32_t u32(const char* section)
    {
        need(4, section);
        const uint32_t v = loadBigEndian32(here());
        mIn.advance(4);
        return v;
    }
    int32_t i32(const char* section) { return static_cast<int32_t>(u32(section)); }
    uint16_t u16(const char* section)
    {
        need(2, section);
        const uint16_t v = loadBigEndian16(here());
        mIn.advance(2);
        return v;
    }
    std::string text(size_t length, const char* section)
    {
        need(length, section);
        std::string s(mIn.here(), length);
        mIn.advance(length);
        return s;
    }
    void skip(size_t bytes, const char* section)
    {
        if (!mIn.skip(bytes)) fail(mPath, std::string("truncated ") + section);
    }
    /// The next 4 bytes as a big-endian word; false at the end of the data.
    bool word(uint32_t& bits)
    {
        if (mIn.available() < 4 && !mIn.ensure(4)) return false;
        bits = loadBigEndian32(here());
        mIn.advance(4);
        return true;
    }

private:
    const unsigned char* here() const { return reinterpret_cast<const unsigned char*>(mIn.here()); }

    StreamReader& mIn;
    const std::string& mPath;
};

struct BgeoAttribute
{
    std::string name;
    int components = 1;
    ScalarType type = ScalarType::Float32;
};

ParticleSet
parseBgeo(StreamReader& stream, const std::string& path)
{
    if (stream.ensure(1) && (stream.here()[0] == 0x7f || stream.here()[0] == '[' || stream.here()[0] == '{')) {
        fail(path, "unsupported BGEO version (JSON-based, Houdini 12 or later); "
                   "only the classic binary BgeoV layout is read: export it from Houdini as .bhclassic");
    }
    if (!stream.ensure(5) || std::memcmp(stream.here(), "BgeoV", 5) != 0) {
        fail(path, "not a BGEO file (no 'BgeoV' magic)");
    }
    BigEndianInput in(stream, path);
    in.skip(5, "BGEO header");
    const int32_t version = in.i32("BGEO header");
    if (version != 5) fail(path, "unsupported BGEO version (" + std::to_string(version) + ")");
    const int32_t pointCount = in.i32("BGEO header");
    for (int i = 0; i < 3; ++i) in.i32("BGEO header");  // primitives, point and prim groups
    const int32_t attributeCount = in.i32("BGEO header");
    for (int i = 0; i < 3; ++i) in.i32("BGEO header");  // vertex, primitive, detail attributes
    if (pointCount < 0 || attributeCount < 0) {
        fail(path, "negative count in BGEO header");
    }

    std::vector<BgeoAttribute> attributes;
    size_t pointBytes = 16;  // x y z w
    for (int32_t a = 0; a < attributeCount; ++a) {
        BgeoAttribute attribute;
        const uint16_t nameLength = in.u16("BGEO attribute table");
        attribute.name = in.text(nameLength, "BGEO attribute table");
        attribute.components = in.u16("BGEO attribute table");
        const int32_t houdiniType = in.i32("BGEO attribute table");
        if (attribute.components == 0) {
            fail(path, "BGEO attribute '" + printable(attribute.name) + "' has 0 components");
        }
        switch (houdiniType) {
        case 0: attribute.type = ScalarType::Float32; break;  // float
        case 1: attribute.type = ScalarType::Int32; break;    // int
        case 5: attribute.type = ScalarType::Float32; break;  // vector
        case 4: {                                             // index: string table
            attribute.type = ScalarType::Int32;
            const int32_t entries = in.i32("BGEO attribute table");
            if (entries < 0) fail(path, "negative string count in BGEO attribute table");
            for (int32_t e = 0; e < entries; ++e) {
                in.skip(in.u16("BGEO attribute table"), "BGEO attribute table");
            }
            break;
        }
        default:
            fail(path, "unsupported BGEO attribute type " + std::to_string(houdiniType) +
                 " of '" + printable(attribute.name) + "'");
        }
        if (houdiniType != 4) in.skip(size_t(attribute.components) * 4, "BGEO attribute table");
        pointBytes += size_t(attribute.components) * 4;
        attributes.push_back(std::move(attribute));
    }

    const uint64_t pointsStart = stream.pos();
    auto truncatedPoints = [&](uint64_t left) {
        fail(path, "truncated BGEO points: header claims " + std::to_string(pointCount) +
             " points of " + std::to_string(pointBytes) + " bytes, " +
             std::to_string(left) + " bytes left");
    };
    // The point block must be able to be present in full before anything is allocated.
    size_t reserved = size_t(pointCount);
    if (!stream.compressed()) {
        if (uint64_t(pointCount) > stream.remaining() / pointBytes) truncatedPoints(stream.remaining());
    } else {
        const uint64_t compressedLeft = stream.rawRemaining();
        const uint64_t mostLeft = stream.available() + compressedLeft * kMaxInflateRatio + 4096;
        if (uint64_t(pointCount) > mostLeft / pointBytes) {
            // Truncated for sure; inflate the rest, keeping nothing, to say by how much.
            stream.drain();
            truncatedPoints(stream.pos() - pointsStart);
        }
        reserved = size_t(std::min<uint64_t>(
            uint64_t(pointCount), (stream.available() + compressedLeft * kTrustedRatio) / pointBytes));
    }

    // In memory: 12 bytes of position (w is dropped) and the attributes' float32 values.
    requireMemoryForParticles(path, reserved, pointBytes - 4);
    ParticleSet particles;
    particles.positions.reserve(reserved);
    particles.attributes.resize(attributes.size());
    for (size_t a = 0; a < attributes.size(); ++a) {
        ParticleAttribute& out = particles.attributes[a];
        out.name = attributes[a].name;
        out.type = attributes[a].type;
        out.components = attributes[a].components;
        out.bytes.reserve(reserved * size_t(out.components) * 4);
    }
    // Uncompressed: one block of all points (the size check above guarantees them);
    // gzip: blocks of kBlockPoints, so the arrays hold only points actually read.
    const size_t blockPoints = stream.compressed() ? kBlockPoints : std::max<size_t>(size_t(pointCount), 1);
    for (size_t done = 0; done < size_t(pointCount);) {
        const size_t end = std::min(size_t(pointCount), done + blockPoints);
        particles.positions.resize(end);
        for (ParticleAttribute& out : particles.attributes) {
            out.bytes.resize(end * size_t(out.components) * 4);
        }
        for (size_t n = done; n < end; ++n) {
            uint32_t bits;
            for (int axis = 0; axis < 4; ++axis) {
                if (!in.word(bits)) truncatedPoints(stream.pos() + stream.available() - pointsStart);
                if (axis < 3) std::memcpy(&particles.positions[n][axis], &bits, 4);
            }
            for (ParticleAttribute& out : particles.attributes) {
                unsigned char* dst = out.bytes.data() + n * size_t(out.components) * 4;
                for (int c = 0; c < out.components; ++c) {
                    if (!in.word(bits)) truncatedPoints(stream.pos() + stream.available() - pointsStart);
                    std::memcpy(dst + 4 * c, &bits, 4);
                }
            }
        }
        done = end;
    }
    // Primitives and the rest are ignored, but a gzip stream is still checked to its end.
    stream.drain();
    return particles;
}

/// parseBgeo(), with gzip errors first (as when the whole file was inflated up front).
ParticleSet
readBgeo(StreamReader& stream, const std::string& path)
{
    try {
        return parseBgeo(stream, path);
    } catch (const FileError&) {
        stream.drain();
        throw;
    }
}

} // namespace

ParticleSet
readBgeoParticles(const char* data, size_t size, const std::string& path)
{
    StreamReader stream(data, size, path, /*inflateGzip=*/true);
    return readBgeo(stream, path);
}

ParticleSet
readBgeoFile(const std::string& path)
{
    StreamReader stream(path, /*inflateGzip=*/true);
    return readBgeo(stream, path);
}

} // namespace io_internal
} // namespace nonbloppy
