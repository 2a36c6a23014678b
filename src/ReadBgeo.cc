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
/// JSON with '['); they are reported as unsupported rather than misread.

#include "Decode.h"
#include "FileFormats.h"
#include "ParticleReaders.h"

#include <nonbloppy/Error.h>

#include <cstring>

namespace nonbloppy {
namespace io_internal {

namespace {

using namespace decode_internal;

/// A bounds-checked big-endian reader over the decompressed bytes.
class BigEndianCursor
{
public:
    BigEndianCursor(const unsigned char* data, size_t size, const std::string& path)
        : mData(data), mSize(size), mPath(path) {}

    size_t left() const { return mSize - mPos; }
    void need(size_t bytes, const char* section) const
    {
        if (bytes > left()) fail(mPath, std::string("truncated ") + section);
    }
    uint32_t u32(const char* section) { need(4, section); mPos += 4; return loadBigEndian32(mData + mPos - 4); }
    int32_t i32(const char* section) { return static_cast<int32_t>(u32(section)); }
    uint16_t u16(const char* section) { need(2, section); mPos += 2; return loadBigEndian16(mData + mPos - 2); }
    std::string text(size_t length, const char* section)
    {
        need(length, section);
        std::string s(reinterpret_cast<const char*>(mData + mPos), length);
        mPos += length;
        return s;
    }
    void skip(size_t bytes, const char* section) { need(bytes, section); mPos += bytes; }
    const unsigned char* here() const { return mData + mPos; }

private:
    const unsigned char* mData;
    size_t mSize;
    size_t mPos = 0;
    const std::string& mPath;
};

struct BgeoAttribute
{
    std::string name;
    int components = 1;
    ScalarType type = ScalarType::Float32;
};

} // namespace

ParticleSet
readBgeoParticles(const char* data, size_t size, const std::string& path)
{
    std::vector<char> inflated;
    if (isGzip(data, size)) {
        inflated = gunzip(data, size, path);
        data = inflated.data();
        size = inflated.size();
    }
    if (size >= 1 && (data[0] == 0x7f || data[0] == '[' || data[0] == '{')) {
        fail(path, "unsupported BGEO version (JSON-based, Houdini 12 or later); "
                   "only the classic binary BgeoV layout is read");
    }
    if (size < 5 || std::memcmp(data, "BgeoV", 5) != 0) {
        fail(path, "not a BGEO file (no 'BgeoV' magic)");
    }
    BigEndianCursor in(reinterpret_cast<const unsigned char*>(data), size, path);
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

    // The point block must be present in full before anything is allocated for it.
    if (uint64_t(pointCount) > in.left() / pointBytes) {
        fail(path, "truncated BGEO points: header claims " + std::to_string(pointCount) +
             " points of " + std::to_string(pointBytes) + " bytes, " +
             std::to_string(in.left()) + " bytes left");
    }
    ParticleSet particles;
    particles.positions.resize(size_t(pointCount));
    particles.attributes.resize(attributes.size());
    for (size_t a = 0; a < attributes.size(); ++a) {
        ParticleAttribute& out = particles.attributes[a];
        out.name = attributes[a].name;
        out.type = attributes[a].type;
        out.components = attributes[a].components;
        out.bytes.resize(size_t(pointCount) * size_t(out.components) * 4);
    }
    const unsigned char* p = in.here();
    for (size_t n = 0; n < size_t(pointCount); ++n) {
        for (int axis = 0; axis < 3; ++axis) {
            const uint32_t bits = loadBigEndian32(p + 4 * axis);
            std::memcpy(&particles.positions[n][axis], &bits, 4);
        }
        p += 16;
        for (ParticleAttribute& out : particles.attributes) {
            unsigned char* dst = out.bytes.data() + n * size_t(out.components) * 4;
            for (int c = 0; c < out.components; ++c) {
                const uint32_t bits = loadBigEndian32(p);
                std::memcpy(dst + 4 * c, &bits, 4);
                p += 4;
            }
        }
    }
    return particles;
}

} // namespace io_internal
} // namespace nonbloppy
