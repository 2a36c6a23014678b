// SPDX-License-Identifier: Apache-2.0
/// @file ReadVtu.cc
/// @brief VTK XML UnstructuredGrid / PolyData particles (`.vtu`, `.vtp`): the XML through
///        pugixml, zlib blocks through zlib, base64 through Base64Reader.
///
/// Data arrays may be `ascii`, inline `binary` (base64) or `appended` (raw or base64),
/// with `vtkZLibDataCompressor` blocks or uncompressed, UInt32 or UInt64 block headers,
/// either byte order. Raw appended data are not XML, so they are cut out of the text
/// before it goes to the XML parser; offsets then index the cut-out bytes.

#include "Decode.h"
#include "FileFormats.h"
#include "ParticleReaders.h"

#include <nonbloppy/Error.h>

#include <pugixml.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string_view>

namespace nonbloppy {
namespace io_internal {

namespace {

using namespace decode_internal;

/// Piece sizes beyond this are rejected outright (and far smaller ones by the byte checks).
constexpr uint64_t kMaxTuples = uint64_t(1) << 40;

bool
vtuScalarType(std::string_view name, ScalarType& type)
{
    static const std::pair<const char*, ScalarType> table[] = {
        {"Int8", ScalarType::Int8}, {"UInt8", ScalarType::UInt8}, {"Int16", ScalarType::Int16},
        {"UInt16", ScalarType::UInt16}, {"Int32", ScalarType::Int32}, {"UInt32", ScalarType::UInt32},
        {"Int64", ScalarType::Int64}, {"UInt64", ScalarType::UInt64},
        {"Float32", ScalarType::Float32}, {"Float64", ScalarType::Float64},
        {"Char", ScalarType::Int8}, {"UChar", ScalarType::UInt8}};
    for (const auto& entry : table) {
        if (name == entry.first) {
            type = entry.second;
            return true;
        }
    }
    return false;
}

/// Where the bytes of binary arrays come from: raw appended bytes, or base64 text.
class ByteSource
{
public:
    virtual ~ByteSource() = default;
    virtual void read(size_t count, std::vector<unsigned char>& out, const std::string& what) = 0;
    virtual size_t maxRemaining() const = 0;
};

class RawSource : public ByteSource
{
public:
    RawSource(const unsigned char* data, size_t size, const std::string& path)
        : mData(data), mSize(size), mPath(path) {}
    void read(size_t count, std::vector<unsigned char>& out, const std::string& what) override
    {
        if (count > mSize - mPos) fail(mPath, "truncated appended data in " + what);
        out.insert(out.end(), mData + mPos, mData + mPos + count);
        mPos += count;
    }
    size_t maxRemaining() const override { return mSize - mPos; }

private:
    const unsigned char* mData;
    size_t mSize;
    size_t mPos = 0;
    const std::string& mPath;
};

class Base64Source : public ByteSource
{
public:
    Base64Source(std::string_view text, const std::string& path) : mReader(text, path) {}
    void read(size_t count, std::vector<unsigned char>& out, const std::string& what) override
    {
        mReader.read(count, out, what);
    }
    size_t maxRemaining() const override { return mReader.maxRemaining(); }

private:
    Base64Reader mReader;
};

struct VtuFile
{
    std::string path;
    bool bigEndian = false;
    bool uint64Headers = false;
    bool zlib = false;
    bool appendedRaw = true;
    const unsigned char* appended = nullptr;  ///< after the '_'
    size_t appendedSize = 0;
    size_t fileSize = 0;
    uint64_t decodedBytes = 0;  ///< all arrays decoded so far
};

uint64_t
headerWord(const std::vector<unsigned char>& bytes, size_t index, const VtuFile& file)
{
    const size_t width = file.uint64Headers ? 8 : 4;
    unsigned char word[8];
    std::memcpy(word, bytes.data() + index * width, width);
    if (file.bigEndian) std::reverse(word, word + width);
    if (width == 4) {
        uint32_t v;
        std::memcpy(&v, word, 4);
        return v;
    }
    uint64_t v;
    std::memcpy(&v, word, 8);
    return v;
}

/// One binary array (header + data, compressed or not) of exactly @a expected bytes.
std::vector<unsigned char>
readBinaryBlock(ByteSource& source, size_t expected, const VtuFile& file, const std::string& what)
{
    const size_t width = file.uint64Headers ? 8 : 4;
    std::vector<unsigned char> header, out;
    if (!file.zlib) {
        source.read(width, header, what);
        const uint64_t bytes = headerWord(header, 0, file);
        if (bytes != expected) {
            fail(file.path, what + " holds " + std::to_string(bytes) + " bytes, expected " +
                 std::to_string(expected));
        }
        if (bytes > source.maxRemaining()) fail(file.path, "truncated data in " + what);
        source.read(size_t(bytes), out, what);
        return out;
    }
    source.read(3 * width, header, what);
    const uint64_t blocks = headerWord(header, 0, file);
    const uint64_t blockSize = headerWord(header, 1, file);
    const uint64_t lastSize = headerWord(header, 2, file);
    if (blocks > source.maxRemaining() / width) fail(file.path, "truncated block header in " + what);
    source.read(size_t(blocks) * width, header, what);
    uint64_t total = 0, compressedTotal = 0;
    if (blocks > 0) {
        if (lastSize > blockSize || blockSize > kMaxTuples) {
            fail(file.path, "corrupt block header in " + what);
        }
        total = (blocks - 1) * blockSize + (lastSize == 0 ? blockSize : lastSize);
    }
    for (uint64_t b = 0; b < blocks; ++b) compressedTotal += headerWord(header, 3 + size_t(b), file);
    if (total != expected) {
        fail(file.path, what + " holds " + std::to_string(total) + " bytes, expected " +
             std::to_string(expected));
    }
    if (compressedTotal > source.maxRemaining()) fail(file.path, "truncated data in " + what);
    out.reserve(size_t(total));
    std::vector<unsigned char> compressed;
    for (uint64_t b = 0; b < blocks; ++b) {
        const uint64_t csize = headerWord(header, 3 + size_t(b), file);
        const uint64_t usize = (b + 1 == blocks && lastSize != 0) ? lastSize : blockSize;
        // Each block fits in what is left of the array (this also catches products above
        // that overflowed), and deflate cannot have packed it tighter than its ratio.
        if (usize > total - out.size() || csize > (uint64_t(1) << 48)
            || usize > csize * kMaxInflateRatio + 64) {
            fail(file.path, "corrupt block header in " + what);
        }
        compressed.clear();
        source.read(size_t(csize), compressed, what);
        inflateZlib(compressed.data(), compressed.size(), size_t(usize), out,
                    "block " + std::to_string(b) + " of " + what, file.path);
    }
    return out;
}

template<typename T>
bool
parseNumber(std::string_view word, unsigned char* out)
{
    if constexpr (std::is_floating_point_v<T>) {
        double value;
        const auto result = std::from_chars(word.data(), word.data() + word.size(), value);
        if (result.ec == std::errc::result_out_of_range) {
            // Denormals and overflow: std::from_chars reports range errors; accept them
            // as 0 or ±inf would hide a corrupt file, so only underflow is tolerated.
            value = std::strtod(std::string(word).c_str(), nullptr);
            if (!std::isfinite(value)) return false;
        } else if (result.ec != std::errc() || result.ptr != word.data() + word.size()) {
            return false;
        }
        const T narrowed = static_cast<T>(value);
        std::memcpy(out, &narrowed, sizeof(T));
        return true;
    } else {
        T value;
        const char* begin = word.data();
        if (!word.empty() && word[0] == '+') ++begin;
        const auto result = std::from_chars(begin, word.data() + word.size(), value);
        if (result.ec != std::errc() || result.ptr != word.data() + word.size()) return false;
        std::memcpy(out, &value, sizeof(T));
        return true;
    }
}

bool
parseTyped(std::string_view word, ScalarType type, unsigned char* out)
{
    switch (type) {
    case ScalarType::Int8: return parseNumber<int8_t>(word, out);
    case ScalarType::UInt8: return parseNumber<uint8_t>(word, out);
    case ScalarType::Int16: return parseNumber<int16_t>(word, out);
    case ScalarType::UInt16: return parseNumber<uint16_t>(word, out);
    case ScalarType::Int32: return parseNumber<int32_t>(word, out);
    case ScalarType::UInt32: return parseNumber<uint32_t>(word, out);
    case ScalarType::Int64: return parseNumber<int64_t>(word, out);
    case ScalarType::UInt64: return parseNumber<uint64_t>(word, out);
    case ScalarType::Float32: return parseNumber<float>(word, out);
    case ScalarType::Float64: return parseNumber<double>(word, out);
    }
    return false;
}

std::vector<unsigned char>
readAsciiArray(std::string_view text, size_t values, ScalarType type, const VtuFile& file,
               const std::string& what)
{
    // Every value takes at least one character and one separator.
    if (values > text.size() / 2 + 1) fail(file.path, "truncated ascii data in " + what);
    const size_t width = scalarSize(type);
    std::vector<unsigned char> out(values * width);
    size_t pos = 0;
    auto isSpace = [](char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; };
    for (size_t i = 0; i < values; ++i) {
        while (pos < text.size() && isSpace(text[pos])) ++pos;
        const size_t start = pos;
        while (pos < text.size() && !isSpace(text[pos])) ++pos;
        if (start == pos) fail(file.path, "truncated ascii data in " + what);
        const std::string_view word = text.substr(start, pos - start);
        if (!parseTyped(word, type, out.data() + i * width)) {
            fail(file.path, "bad value '" + printable(word) + "' in " + what);
        }
    }
    return out;
}

/// The values of one DataArray, native byte order: tuples × components × type size bytes.
std::vector<unsigned char>
readDataArray(const pugi::xml_node& node, size_t tuples, ScalarType type, int components,
              VtuFile& file, const std::string& what)
{
    const size_t width = scalarSize(type);
    const uint64_t expected = uint64_t(tuples) * uint64_t(components) * width;
    // No encoding packs data tighter than deflate's ratio; that bounds all arrays together
    // too, since pieces could otherwise decode the same appended bytes again and again.
    file.decodedBytes += expected;
    if (expected > uint64_t(file.fileSize) * kMaxInflateRatio + 1024
        || file.decodedBytes > uint64_t(file.fileSize) * kMaxInflateRatio + 1024) {
        fail(file.path, "truncated " + what + ": the file is too small for " +
             std::to_string(tuples) + " tuples");
    }
    const std::string format = node.attribute("format").as_string("ascii");
    std::vector<unsigned char> bytes;
    if (format == "ascii") {
        return readAsciiArray(node.child_value(), size_t(tuples) * size_t(components), type, file, what);
    } else if (format == "binary") {
        Base64Source source(node.child_value(), file.path);
        bytes = readBinaryBlock(source, size_t(expected), file, what);
    } else if (format == "appended") {
        if (file.appended == nullptr) fail(file.path, what + " is appended but there is no AppendedData");
        const char* offsetText = node.attribute("offset").as_string("");
        uint64_t offset = 0;
        const auto result = std::from_chars(offsetText, offsetText + std::strlen(offsetText), offset);
        if (result.ec != std::errc() || *result.ptr != '\0') {
            fail(file.path, "bad offset '" + printable(offsetText) + "' of " + what);
        }
        if (offset > file.appendedSize) fail(file.path, "offset of " + what + " lies beyond the appended data");
        std::unique_ptr<ByteSource> source;
        if (file.appendedRaw) {
            source = std::make_unique<RawSource>(file.appended + offset, file.appendedSize - size_t(offset), file.path);
        } else {
            source = std::make_unique<Base64Source>(
                std::string_view(reinterpret_cast<const char*>(file.appended) + offset,
                                 file.appendedSize - size_t(offset)), file.path);
        }
        bytes = readBinaryBlock(*source, size_t(expected), file, what);
    } else {
        fail(file.path, "unknown format '" + printable(format) + "' of " + what);
    }
    if (file.bigEndian) swapBytes(bytes.data(), bytes.size() / width, width);
    return bytes;
}

/// Cut raw appended data out of the text so the rest can be parsed as XML.
std::string
locateAppendedData(const char* data, size_t size, VtuFile& file)
{
    const std::string_view text(data, size);
    const size_t tag = text.find("<AppendedData");
    if (tag == std::string_view::npos) return std::string(text);
    const size_t tagEnd = text.find('>', tag);
    if (tagEnd == std::string_view::npos) fail(file.path, "truncated AppendedData tag");
    const std::string_view tagText = text.substr(tag, tagEnd - tag);
    file.appendedRaw = tagText.find("\"base64\"") == std::string_view::npos
                       && tagText.find("'base64'") == std::string_view::npos;
    size_t underscore = tagEnd + 1;
    while (underscore < size && (text[underscore] == ' ' || text[underscore] == '\n'
                                 || text[underscore] == '\r' || text[underscore] == '\t')) {
        ++underscore;
    }
    if (underscore >= size || text[underscore] != '_') {
        fail(file.path, "AppendedData does not start with '_'");
    }
    const size_t close = text.rfind("</AppendedData>");
    if (close == std::string_view::npos || close <= underscore) {
        fail(file.path, "truncated AppendedData (no </AppendedData>)");
    }
    file.appended = reinterpret_cast<const unsigned char*>(data) + underscore + 1;
    file.appendedSize = close - underscore - 1;
    std::string xml(text.substr(0, underscore + 1));
    xml.append(text.substr(close));
    return xml;
}

} // namespace

ParticleSet
readVtuParticles(const char* data, size_t size, const std::string& path)
{
    VtuFile file;
    file.path = path;
    file.fileSize = size;
    const std::string xml = locateAppendedData(data, size, file);

    pugi::xml_document document;
    const pugi::xml_parse_result parsed =
        document.load_buffer(xml.data(), xml.size(), pugi::parse_default, pugi::encoding_utf8);
    if (!parsed) {
        fail(path, std::string("XML error at byte ") + std::to_string(parsed.offset) + ": " +
             parsed.description());
    }
    const pugi::xml_node root = document.child("VTKFile");
    if (!root) fail(path, "no VTKFile element");
    const std::string type = root.attribute("type").as_string();
    if (type != "UnstructuredGrid" && type != "PolyData") {
        fail(path, "unsupported VTKFile type '" + printable(type) +
             "'; expected UnstructuredGrid or PolyData");
    }
    const std::string byteOrder = root.attribute("byte_order").as_string("LittleEndian");
    if (byteOrder != "LittleEndian" && byteOrder != "BigEndian") {
        fail(path, "unknown byte_order '" + printable(byteOrder) + "'");
    }
    file.bigEndian = byteOrder == "BigEndian";
    const std::string headerType = root.attribute("header_type").as_string("UInt32");
    if (headerType != "UInt32" && headerType != "UInt64") {
        fail(path, "unsupported header_type '" + printable(headerType) + "'");
    }
    file.uint64Headers = headerType == "UInt64";
    const std::string compressor = root.attribute("compressor").as_string("");
    if (!compressor.empty() && compressor != "vtkZLibDataCompressor") {
        fail(path, "unsupported compressor '" + printable(compressor) +
             "'; only vtkZLibDataCompressor is read");
    }
    file.zlib = !compressor.empty();

    const pugi::xml_node grid = root.child(type.c_str());
    if (!grid) fail(path, "no " + type + " element");

    ParticleSet particles;
    bool first = true;
    for (const pugi::xml_node piece : grid.children("Piece")) {
        const char* countText = piece.attribute("NumberOfPoints").as_string("");
        uint64_t count = 0;
        const auto result = std::from_chars(countText, countText + std::strlen(countText), count);
        if (result.ec != std::errc() || *result.ptr != '\0' || count > kMaxTuples) {
            fail(path, "bad NumberOfPoints '" + printable(countText) + "'");
        }
        const size_t offset = particles.positions.size();
        if (count > 0) {
            const pugi::xml_node points = piece.child("Points").child("DataArray");
            if (!points) fail(path, "piece without Points");
            ScalarType pointType;
            if (!vtuScalarType(points.attribute("type").as_string(), pointType)
                || (pointType != ScalarType::Float32 && pointType != ScalarType::Float64)) {
                fail(path, "Points must be Float32 or Float64, got '" +
                     printable(points.attribute("type").as_string()) + "'");
            }
            if (points.attribute("NumberOfComponents").as_int(1) != 3) {
                fail(path, "Points must have 3 components");
            }
            const std::vector<unsigned char> bytes =
                readDataArray(points, size_t(count), pointType, 3, file, "Points");
            particles.positions.resize(offset + size_t(count));
            for (size_t i = 0; i < size_t(count) * 3; ++i) {
                float value;
                if (pointType == ScalarType::Float32) {
                    std::memcpy(&value, bytes.data() + 4 * i, 4);
                } else {
                    double wide;
                    std::memcpy(&wide, bytes.data() + 8 * i, 8);
                    value = static_cast<float>(wide);
                }
                particles.positions[offset + i / 3][int(i % 3)] = value;
            }
        }

        size_t index = 0;
        for (const pugi::xml_node array : piece.child("PointData").children("DataArray")) {
            const std::string name = array.attribute("Name").as_string("");
            const std::string what = "'" + printable(name) + "'";
            ScalarType valueType;
            if (!vtuScalarType(array.attribute("type").as_string(), valueType)) {
                fail(path, "unsupported type '" + printable(array.attribute("type").as_string()) +
                     "' of " + what);
            }
            const int components = array.attribute("NumberOfComponents").as_int(1);
            if (components < 1 || components > 64) {
                fail(path, "bad NumberOfComponents of " + what);
            }
            std::vector<unsigned char> bytes =
                count > 0 ? readDataArray(array, size_t(count), valueType, components, file, what)
                          : std::vector<unsigned char>();
            if (first) {
                ParticleAttribute attribute;
                attribute.name = name;
                attribute.type = valueType;
                attribute.components = components;
                attribute.bytes = std::move(bytes);
                particles.attributes.push_back(std::move(attribute));
            } else {
                if (index >= particles.attributes.size()
                    || particles.attributes[index].name != name
                    || particles.attributes[index].type != valueType
                    || particles.attributes[index].components != components) {
                    fail(path, "pieces have different point data (" + what + ")");
                }
                auto& dst = particles.attributes[index].bytes;
                dst.insert(dst.end(), bytes.begin(), bytes.end());
            }
            ++index;
        }
        if (!first && index != particles.attributes.size()) {
            fail(path, "pieces have different point data");
        }
        first = false;
    }
    if (first) fail(path, "no Piece in " + type);
    return particles;
}

} // namespace io_internal
} // namespace nonbloppy
