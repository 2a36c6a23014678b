// SPDX-License-Identifier: Apache-2.0
/// @file FileFormats.cc
/// @brief Legacy VTK and PLY decoding shared by readParticles() and readMesh(), and the
///        file, text, number and type-name helpers that the streaming readers use too.

#include "FileFormats.h"
#include "MachineMemory.h"

#include <nonbloppy/Error.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <stdlib.h>
#include <cstring>
#include <locale.h>
#include <limits>
#include <memory>
#include <string_view>
#include <unordered_set>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace nonbloppy {
namespace io_internal {

// ------------------------------------------------------------------------------------------
// Files, messages, text

[[noreturn]] void
failRead(const std::string& path, int errorNumber)
{
    throw FileError("cannot read " + path + ": " + std::strerror(errorNumber));
}

OpenFile
openFile(const std::string& path)
{
    OpenFile file;
    file.fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (file.fd < 0) throw FileError("cannot open " + path + ": " + std::strerror(errno));
    struct stat info;
    const int error = (::fstat(file.fd, &info) != 0) ? errno : S_ISDIR(info.st_mode) ? EISDIR : 0;
    if (error != 0) {
        ::close(file.fd);
        failRead(path, error);
    }
    file.regular = S_ISREG(info.st_mode);
    file.size = uint64_t(info.st_size);
    return file;
}

std::vector<char>
loadFile(const std::string& path)
{
    const OpenFile file = openFile(path);
    // st_size is only a hint (pipes and /proc files report 0).
    return readToEndAndClose(file.fd, path, file.regular ? size_t(file.size) : 0);
}

std::vector<char>
loadFileThrough(const std::string& path, std::string_view marker)
{
    const OpenFile file = openFile(path);
    struct FdCloser { int fd; ~FdCloser() { ::close(fd); } } closer{file.fd};
    constexpr size_t kPiece = 65536;
    std::vector<char> data;
    size_t used = 0;
    size_t searchFrom = 0;
    for (;;) {
        data.resize(used + kPiece);
        const ssize_t n = ::read(file.fd, data.data() + used, kPiece);
        if (n < 0) {
            if (errno == EINTR) continue;
            failRead(path, errno);
        }
        if (n == 0) break;
        used += size_t(n);
        const std::string_view seen(data.data(), used);
        const size_t at = seen.find(marker, searchFrom);
        if (at != std::string_view::npos && seen.find('\n', at) != std::string_view::npos) break;
        // A marker may straddle two pieces.
        searchFrom = used >= marker.size() ? used - marker.size() : 0;
    }
    data.resize(used);
    return data;
}

std::vector<char>
readToEndAndClose(int fd, const std::string& path, size_t sizeHint)
{
    struct FdCloser { int fd; ~FdCloser() { ::close(fd); } } closer{fd};
    std::vector<char> data(sizeHint > 0 ? sizeHint + 1 : 65536);
    size_t used = 0;
    for (;;) {
        if (used == data.size()) data.resize(data.size() * 2);
        const ssize_t n = ::read(fd, data.data() + used, data.size() - used);
        if (n < 0) {
            if (errno == EINTR) continue;
            failRead(path, errno);
        }
        if (n == 0) break;
        used += size_t(n);
    }
    data.resize(used);
    return data;
}

std::string
lowerExtension(const std::string& path)
{
    const size_t slash = path.find_last_of('/');
    const size_t nameStart = (slash == std::string::npos) ? 0 : slash + 1;
    const size_t dot = path.find_last_of('.');
    if (dot == std::string::npos || dot <= nameStart) return std::string();
    std::string ext = path.substr(dot);
    for (char& ch : ext) {
        if (ch >= 'A' && ch <= 'Z') ch = char(ch - 'A' + 'a');
    }
    return ext;
}

bool
isMeshExtension(const std::string& ext)
{
    return ext == ".obj" || ext == ".ply" || ext == ".vtk";
}

std::string
requireMeshExtension(const std::string& path)
{
    const std::string ext = lowerExtension(path);
    if (ext.empty()) {
        throw FileError("mesh file name has no extension (" + path + "); expected .obj, .ply or .vtk");
    }
    if (!isMeshExtension(ext)) {
        throw FileError("unknown mesh file extension '" + ext + "' (" + path + "); expected .obj, .ply or .vtk");
    }
    return ext;
}

void
fail(const std::string& path, const std::string& what)
{
    throw FileError(what + " (" + path + ")");
}

void
requireMemoryForParticles(const std::string& path, uint64_t count, uint64_t bytesPerParticle)
{
    const double bytes = double(count) * double(bytesPerParticle);
    const double headroom = machine_memory_internal::memoryHeadroomBytes();
    if (!(headroom >= 0.0) || !(bytes > headroom)) return;
    fail(path, std::to_string(count) + " particles would take " + machine_memory_internal::formatBytes(bytes) +
        " of memory, more than the " + machine_memory_internal::formatBytes(headroom) +
        " this process can still take");
}

namespace {

std::string
lowerCase(std::string_view text)
{
    std::string out(text);
    for (char& c : out) c = toLower(c);
    return out;
}

/// The component number @a digits spells: 0 to kMaxFileComponents - 1 without a leading
/// zero; -1 otherwise.
int componentNumber(std::string_view digits)
{
    if (digits.empty() || digits.size() > 4 || (digits.size() > 1 && digits[0] == '0')) return -1;
    int number = 0;
    for (char c : digits) {
        if (c < '0' || c > '9') return -1;
        number = number * 10 + (c - '0');
    }
    return number < kMaxFileComponents ? number : -1;
}

} // namespace

int
tableComponentOf(const std::string& name, std::string& base)
{
    static const char* letters[3][2] = {{"_x", ".x"}, {"_y", ".y"}, {"_z", ".z"}};
    const std::string low = lowerCase(name);
    for (int c = 0; c < 3; ++c) {
        for (const char* suffix : letters[c]) {
            const size_t n = std::strlen(suffix);
            if (low.size() > n && low.compare(low.size() - n, n, suffix) == 0) {
                base = name.substr(0, name.size() - n);
                return c;
            }
        }
    }
    // name:c (ParaView's spelling, and writeParticles()') or name[c]; not name_c, which
    // tables use for scalars of their own ("p_1", "w_0").
    const bool bracket = !name.empty() && name.back() == ']';
    const size_t open = bracket ? name.rfind('[') : name.rfind(':');
    if (open == std::string::npos || open == 0) return -1;
    const size_t end = bracket ? name.size() - 1 : name.size();
    const int component = componentNumber(std::string_view(name).substr(open + 1, end - open - 1));
    if (component < 0) return -1;
    base = name.substr(0, open);
    return component;
}

int
suffixComponentOf(const std::string& name, std::string& base)
{
    const size_t underscore = name.rfind('_');
    if (underscore == std::string::npos || underscore == 0 || underscore + 1 == name.size()) return -1;
    const std::string_view suffix = std::string_view(name).substr(underscore + 1);
    const int component = suffix.size() == 1 && suffix[0] >= 'x' && suffix[0] <= 'z' ? suffix[0] - 'x'
                                                                                    : componentNumber(suffix);
    if (component < 0) return -1;
    base = name.substr(0, underscore);
    return component;
}

int
tablePositionAxis(const std::string& name)
{
    const std::string low = lowerCase(name);
    if (low == "x" || low == "y" || low == "z") return low[0] - 'x';
    std::string base;
    const int component = tableComponentOf(name, base);
    const std::string lowBase = lowerCase(base);
    const bool positionBase = lowBase == "points" || lowBase == "position" || lowBase == "pos" || lowBase == "p";
    return component >= 0 && component < 3 && positionBase ? component : -1;
}

std::vector<ColumnGroup>
groupColumns(const std::vector<AttributeColumn>& columns)
{
    std::vector<ColumnGroup> runs;  // each run's base in name until it is settled
    for (size_t i = 0; i < columns.size(); ++i) {
        const AttributeColumn& column = columns[i];
        if (column.component > 0 && !runs.empty()) {
            ColumnGroup& previous = runs.back();
            const AttributeColumn& last = columns[previous.columns.back()];
            if (last.index + 1 == column.index && last.kind == column.kind && last.component >= 0
                && previous.name == column.base && int(previous.columns.size()) == column.component) {
                previous.columns.push_back(i);
                continue;
            }
        }
        runs.push_back(ColumnGroup{column.component == 0 ? column.base : column.name, {i}});
    }
    // A set, not a scan per run: 60,000 columns took 10 s (bug hunt).
    std::unordered_set<std::string_view> names;
    for (const AttributeColumn& column : columns) names.insert(column.name);
    // A base an earlier run took stays with it: v_x v_y v_z then v_0 v_1 made two
    // attributes 'v' (PLY), of which mesh --attributes kept one, or refused the file (CSV).
    std::unordered_set<std::string> grouped;
    std::vector<ColumnGroup> groups;
    for (ColumnGroup& run : runs) {
        if (run.columns.size() >= 2 && names.count(run.name) == 0 && grouped.insert(run.name).second) {
            groups.push_back(std::move(run));
        } else {
            for (size_t i : run.columns) groups.push_back(ColumnGroup{columns[i].name, {i}});
        }
    }
    return groups;
}

std::string
printable(std::string_view text, size_t maxLength)
{
    std::string result;
    for (char ch : text.substr(0, maxLength)) {
        result += (ch >= 32 && ch < 127) ? ch : '?';
    }
    if (text.size() > maxLength) result += "...";
    return result;
}

bool
iequals(std::string_view a, std::string_view b)
{
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i) {
        if (toLower(a[i]) != toLower(b[i])) return false;
    }
    return true;
}

std::string_view
trim(std::string_view text)
{
    while (!text.empty() && isSpace(text.front())) text.remove_prefix(1);
    while (!text.empty() && isSpace(text.back())) text.remove_suffix(1);
    return text;
}

std::vector<std::string_view>
splitWords(std::string_view text)
{
    std::vector<std::string_view> words;
    size_t i = 0;
    while (i < text.size()) {
        while (i < text.size() && isSpace(text[i])) ++i;
        const size_t begin = i;
        while (i < text.size() && !isSpace(text[i])) ++i;
        if (i > begin) words.push_back(text.substr(begin, i - begin));
    }
    return words;
}

std::string
upper(std::string_view text)
{
    std::string result(text);
    for (char& ch : result) {
        if (ch >= 'a' && ch <= 'z') ch = char(ch - 'a' + 'A');
    }
    return result;
}

// ------------------------------------------------------------------------------------------
// Numbers

bool
parseCount(std::string_view text, uint64_t& value)
{
    const char* end = text.data() + text.size();
    const auto result = std::from_chars(text.data(), end, value);
    return !text.empty() && result.ec == std::errc() && result.ptr == end;
}

std::errc
parseDoubleText(std::string_view text, double& value)
{
    if (!text.empty() && text.front() == '+') text.remove_prefix(1);
    if (text.empty()) return std::errc::invalid_argument;
    const char* end = text.data() + text.size();
    const auto result = std::from_chars(text.data(), end, value);
    if (result.ec == std::errc() && result.ptr == end) return std::errc();
    if (result.ec != std::errc::result_out_of_range || text.size() >= 64) return std::errc::invalid_argument;
    // from_chars leaves the value unset for 1e-310 (a denormal), 1e-400 or 1e400; strtod
    // gives it, in a C locale of our own (one per process, never changed).
    static const locale_t cLocale = ::newlocale(LC_ALL_MASK, "C", locale_t(0));
    if (cLocale == locale_t(0)) return std::errc::invalid_argument;  // out of memory at first use
    const std::string copy(text);
    char* parsedEnd = nullptr;
    value = ::strtod_l(copy.c_str(), &parsedEnd, cLocale);
    return parsedEnd == copy.c_str() + copy.size() ? std::errc::result_out_of_range : std::errc::invalid_argument;
}

namespace {

bool
parseDouble(std::string_view text, double& value)
{
    return parseDoubleText(text, value) != std::errc::invalid_argument;
}

template<typename IntT, typename WideT>
bool
parseNarrow(std::string_view text, unsigned char* out)
{
    WideT wide;
    if (!parseWhole(text, wide)) return false;
    if (wide < WideT(std::numeric_limits<IntT>::min()) ||
        wide > WideT(std::numeric_limits<IntT>::max())) return false;
    const IntT value = IntT(wide);
    std::memcpy(out, &value, sizeof(IntT));
    return true;
}

} // namespace

/// Parse one text value of @a type into native bytes at @a out.
bool
parseTextValue(std::string_view text, ScalarType type, unsigned char* out)
{
    switch (type) {
        case ScalarType::Int8: return parseNarrow<int8_t, int64_t>(text, out);
        case ScalarType::UInt8: return parseNarrow<uint8_t, uint64_t>(text, out);
        case ScalarType::Int16: return parseNarrow<int16_t, int64_t>(text, out);
        case ScalarType::UInt16: return parseNarrow<uint16_t, uint64_t>(text, out);
        case ScalarType::Int32: return parseNarrow<int32_t, int64_t>(text, out);
        case ScalarType::UInt32: return parseNarrow<uint32_t, uint64_t>(text, out);
        case ScalarType::Int64: return parseNarrow<int64_t, int64_t>(text, out);
        case ScalarType::UInt64: return parseNarrow<uint64_t, uint64_t>(text, out);
        case ScalarType::Float32: {
            double value;
            if (!parseDouble(text, value)) return false;
            const float narrow = float(value);
            std::memcpy(out, &narrow, sizeof(float));
            return true;
        }
        case ScalarType::Float64: {
            double value;
            if (!parseDouble(text, value)) return false;
            std::memcpy(out, &value, sizeof(double));
            return true;
        }
    }
    return false;
}

namespace {

/// Apply @a swap to each of @a count unaligned UIntT values at @a data.
template<typename UIntT, typename SwapT>
void
swapEach(unsigned char* data, size_t count, SwapT swap)
{
    for (size_t i = 0; i < count; ++i) {
        UIntT v;
        std::memcpy(&v, data + sizeof(UIntT) * i, sizeof(UIntT));
        v = swap(v);
        std::memcpy(data + sizeof(UIntT) * i, &v, sizeof(UIntT));
    }
}

} // namespace

void
swapInPlace(unsigned char* data, size_t count, size_t width)
{
    switch (width) {
        case 2: swapEach<uint16_t>(data, count, [](uint16_t v) { return __builtin_bswap16(v); }); break;
        case 4: swapEach<uint32_t>(data, count, [](uint32_t v) { return __builtin_bswap32(v); }); break;
        case 8: swapEach<uint64_t>(data, count, [](uint64_t v) { return __builtin_bswap64(v); }); break;
        default: break;
    }
}

double
valueAsDouble(const unsigned char* p, ScalarType type)
{
    switch (type) {
        case ScalarType::Float32: { float v; std::memcpy(&v, p, 4); return v; }
        case ScalarType::Float64: { double v; std::memcpy(&v, p, 8); return v; }
        case ScalarType::UInt64: { uint64_t v; std::memcpy(&v, p, 8); return double(v); }
        default: {
            int64_t v = 0;
            integerValue(p, type, v);
            return double(v);
        }
    }
}

/// Integer value of @a p (native bytes of integer @a type); false if it does not fit int64.
bool
integerValue(const unsigned char* p, ScalarType type, int64_t& value)
{
    switch (type) {
        case ScalarType::Int8: { int8_t v; std::memcpy(&v, p, 1); value = v; return true; }
        case ScalarType::UInt8: { uint8_t v; std::memcpy(&v, p, 1); value = v; return true; }
        case ScalarType::Int16: { int16_t v; std::memcpy(&v, p, 2); value = v; return true; }
        case ScalarType::UInt16: { uint16_t v; std::memcpy(&v, p, 2); value = v; return true; }
        case ScalarType::Int32: { int32_t v; std::memcpy(&v, p, 4); value = v; return true; }
        case ScalarType::UInt32: { uint32_t v; std::memcpy(&v, p, 4); value = v; return true; }
        case ScalarType::Int64: { std::memcpy(&value, p, 8); return true; }
        case ScalarType::UInt64: {
            uint64_t v;
            std::memcpy(&v, p, 8);
            value = int64_t(v);
            return v <= uint64_t(std::numeric_limits<int64_t>::max());
        }
        default: return false;
    }
}

void
requireFileComponents(const std::string& name, int components, const std::string& suffix)
{
    if (components > kMaxFileComponents) {
        throw ParameterError("attribute '" + name + "' has " + std::to_string(components) + " components, more than the " +
                             std::to_string(kMaxFileComponents) + " a file holds" + suffix);
    }
}

void
requireCountableValues(const ParticleAttribute& attribute, const std::string& suffix)
{
    if (attribute.components < 1) {
        throw ParameterError("attribute '" + attribute.name + "' has " + std::to_string(attribute.components) +
                             " components, at least 1 needed" + suffix);
    }
    if (scalarSize(attribute.type) == 0) {
        throw ParameterError("attribute '" + attribute.name + "' has the unknown scalar type " +
                             std::to_string(int(attribute.type)) + suffix);
    }
}

void
requireOneValuePerParticle(const ParticleSet& particles, const std::string& suffix)
{
    for (const ParticleAttribute& a : particles.attributes) {
        requireCountableValues(a, suffix);
        if (a.size() != particles.size()
            || a.bytes.size() != particles.size() * size_t(a.components) * scalarSize(a.type)) {
            throw ParameterError("attribute '" + a.name + "' does not hold one value per particle" + suffix);
        }
    }
}

void
requireInt64Values(const ParticleAttribute& attribute, const char* holder)
{
    if (attribute.type != ScalarType::UInt64) return;
    for (size_t at = 0; at + 8 <= attribute.bytes.size(); at += 8) {
        uint64_t value;
        std::memcpy(&value, attribute.bytes.data() + at, 8);
        if (value > uint64_t(std::numeric_limits<int64_t>::max())) {
            throw ParameterError("attribute '" + attribute.name + "' holds " + std::to_string(value) +
                                 ", above 9223372036854775807, the largest integer " + holder);
        }
    }
}

bool
holdsIntegersPastDouble(const ParticleAttribute& attribute)
{
    const bool isSigned = attribute.type == ScalarType::Int64;
    if (!isSigned && attribute.type != ScalarType::UInt64) return false;
    for (size_t at = 0; at + 8 <= attribute.bytes.size(); at += 8) {
        uint64_t bits;
        std::memcpy(&bits, attribute.bytes.data() + at, 8);
        const bool exact = isSigned ? exactInDouble(int64_t(bits)) : bits <= uint64_t(kExactInDouble);
        if (!exact) return true;
    }
    return false;
}

ScalarType
plyIntegerType(int64_t lowest, int64_t highest)
{
    if (lowest >= std::numeric_limits<int32_t>::min() && highest <= std::numeric_limits<int32_t>::max()) {
        return ScalarType::Int32;
    }
    if (lowest >= 0 && highest <= int64_t(std::numeric_limits<uint32_t>::max())) return ScalarType::UInt32;
    return ScalarType::Float64;
}

const char*
plyTypeName(ScalarType type)
{
    switch (type) {
    case ScalarType::Int8: return "char";
    case ScalarType::UInt8: return "uchar";
    case ScalarType::Int16: return "short";
    case ScalarType::UInt16: return "ushort";
    case ScalarType::Int32: return "int";
    case ScalarType::UInt32: return "uint";
    case ScalarType::Float32: return "float";
    default: return "double";  // Float64, and 64-bit integers (PLY has none)
    }
}

const char*
vtkTypeName(ScalarType type)
{
    switch (type) {
    case ScalarType::Int8: return "char";
    case ScalarType::UInt8: return "unsigned_char";
    case ScalarType::Int16: return "short";
    case ScalarType::UInt16: return "unsigned_short";
    case ScalarType::Int32: return "int";
    case ScalarType::UInt32: return "unsigned_int";
    case ScalarType::Int64: return "vtktypeint64";
    case ScalarType::UInt64: return "vtktypeuint64";
    case ScalarType::Float32: return "float";
    case ScalarType::Float64: return "double";
    }
    return "double";
}

// ------------------------------------------------------------------------------------------
// Inputs and typed values

namespace {

/// A read position in a memory buffer.
class Cursor final : public ByteInput
{
public:
    Cursor(const char* data, size_t size) : mData(data), mSize(size) {}

    uint64_t remaining() const override { return mSize - mPos; }
    bool atEnd() override { return mPos >= mSize; }

    void skipSpace() override
    {
        while (mPos < mSize && isSpace(mData[mPos])) ++mPos;
    }

    std::string_view token() override
    {
        skipSpace();
        const size_t begin = mPos;
        while (mPos < mSize && !isSpace(mData[mPos])) ++mPos;
        return std::string_view(mData + begin, mPos - begin);
    }

    std::string line() override
    {
        const size_t begin = mPos;
        const void* newline = std::memchr(mData + mPos, '\n', mSize - mPos);
        size_t end = newline ? size_t(static_cast<const char*>(newline) - mData) : mSize;
        mPos = newline ? end + 1 : mSize;
        if (end > begin && mData[end - 1] == '\r') --end;
        return std::string(mData + begin, end - begin);
    }

    bool peekWord(std::string_view word) override
    {
        const size_t saved = mPos;
        const std::string_view next = token();
        mPos = saved;
        return iequals(next, word);
    }

    bool skipLineStartingWith(std::string_view word, bool skipSpaceFirst) override
    {
        const size_t saved = mPos;
        if (skipSpaceFirst) skipSpace();
        if (mSize - mPos >= word.size() &&
            iequals(std::string_view(mData + mPos, word.size()), word)) {
            line();
            return true;
        }
        mPos = saved;
        return false;
    }

    bool readBytes(unsigned char* dst, size_t n) override
    {
        if (n > mSize - mPos) {
            mPos = mSize;
            return false;
        }
        if (n > 0) std::memcpy(dst, mData + mPos, n);
        mPos += n;
        return true;
    }

    void skipBytes(uint64_t n) override { mPos += size_t(std::min<uint64_t>(n, mSize - mPos)); }

private:
    const char* mData;
    size_t mSize;
    size_t mPos = 0;
};

} // namespace

void
ValueReader::requireRoom(uint64_t count, ScalarType type, const std::string& section) const
{
    const uint64_t left = mInput.remaining();
    // A text value takes at least one character plus a separator.
    const uint64_t capacity = mBinary ? left / scalarSize(type) : (left + 1) / 2;
    if (count > capacity) fail(mPath, "truncated " + section);
}

void
ValueReader::read(uint64_t count, ScalarType type, const std::string& section,
                  std::vector<unsigned char>& out)
{
    requireRoom(count, type, section);
    const size_t start = out.size();
    out.resize(start + size_t(count) * scalarSize(type));
    readInto(size_t(count), type, section, out.data() + start);
}

void
ValueReader::readInto(size_t count, ScalarType type, const std::string& section,
                      unsigned char* dst)
{
    requireRoom(count, type, section);
    const size_t width = scalarSize(type);
    if (mBinary) {
        if (!mInput.readBytes(dst, count * width)) fail(mPath, "truncated " + section);
        if (mSwap && width > 1) swapInPlace(dst, count, width);
        return;
    }
    for (size_t i = 0; i < count; ++i) {
        const std::string_view text = mInput.token();
        if (text.empty()) fail(mPath, "truncated " + section);
        if (!parseTextValue(text, type, dst + i * width)) {
            fail(mPath, "bad " + std::string(scalarTypeName(type)) + " value '" +
                printable(text) + "' in " + section);
        }
    }
}

void
ValueReader::readFloats(size_t count, ScalarType type, const std::string& section, float* dst)
{
    requireRoom(count, type, section);
    if (type == ScalarType::Float32) {
        readInto(count, type, section, reinterpret_cast<unsigned char*>(dst));
        return;
    }
    std::vector<double> values(std::min<size_t>(count, kChunkBytes / sizeof(double)));
    for (size_t done = 0; done < count;) {
        const size_t n = std::min(values.size(), count - done);
        readInto(n, type, section, reinterpret_cast<unsigned char*>(values.data()));
        for (size_t i = 0; i < n; ++i) dst[done + i] = float(values[i]);
        done += n;
    }
}

void
ValueReader::skip(uint64_t count, ScalarType type, const std::string& section)
{
    requireRoom(count, type, section);
    if (mBinary) {
        mInput.skipBytes(count * scalarSize(type));
        return;
    }
    for (uint64_t i = 0; i < count; ++i) {
        if (mInput.token().empty()) fail(mPath, "truncated " + section);
    }
}

int64_t
ValueReader::readInteger(ScalarType type, const std::string& section)
{
    unsigned char bytes[8];
    readInto(1, type, section, bytes);
    int64_t value = 0;
    if (!integerValue(bytes, type, value)) fail(mPath, "integer out of range in " + section);
    return value;
}

namespace {

std::vector<int64_t>
toIntegers(const std::vector<unsigned char>& bytes, ScalarType type, const std::string& path,
           const std::string& section)
{
    const size_t width = scalarSize(type);
    std::vector<int64_t> values(bytes.size() / width);
    for (size_t i = 0; i < values.size(); ++i) {
        if (!integerValue(bytes.data() + i * width, type, values[i])) {
            fail(path, "integer out of range in " + section);
        }
    }
    return values;
}

uint32_t
checkedIndex(int64_t value, const std::string& path, const std::string& section)
{
    if (value < 0 || value > int64_t(std::numeric_limits<uint32_t>::max())) {
        fail(path, "bad vertex index " + std::to_string(value) + " in " + section);
    }
    return uint32_t(value);
}

} // namespace

std::vector<float>
toFloats(const NumericArray& array)
{
    const size_t width = scalarSize(array.type);
    const size_t count = array.bytes.size() / width;
    std::vector<float> values(count);
    if (array.type == ScalarType::Float32) {
        if (count > 0) std::memcpy(values.data(), array.bytes.data(), count * sizeof(float));
    } else {
        for (size_t i = 0; i < count; ++i) {
            values[i] = float(valueAsDouble(array.bytes.data() + i * width, array.type));
        }
    }
    return values;
}


// ------------------------------------------------------------------------------------------
// Type names

namespace {

struct TypeName
{
    const char* name;
    ScalarType type;
};

template<size_t SizeT>
bool
findTypeName(const TypeName (&table)[SizeT], std::string_view name, bool ignoreCase,
             ScalarType& type)
{
    for (const TypeName& entry : table) {
        if (ignoreCase ? iequals(name, entry.name) : name == entry.name) {
            type = entry.type;
            return true;
        }
    }
    return false;
}

} // namespace

// ------------------------------------------------------------------------------------------
// Legacy VTK

bool
vtkScalarType(std::string_view name, ScalarType& type)
{
    // "long" is 8 bytes as VTK writes it on Linux/macOS; VTK's legacy writer stores
    // vtkIdType arrays as 32-bit int for backward compatibility.
    static const TypeName kTable[] = {
        {"char", ScalarType::Int8}, {"signed_char", ScalarType::Int8},
        {"vtktypeint8", ScalarType::Int8},
        {"unsigned_char", ScalarType::UInt8}, {"vtktypeuint8", ScalarType::UInt8},
        {"short", ScalarType::Int16}, {"vtktypeint16", ScalarType::Int16},
        {"unsigned_short", ScalarType::UInt16}, {"vtktypeuint16", ScalarType::UInt16},
        {"int", ScalarType::Int32}, {"vtktypeint32", ScalarType::Int32},
        {"vtkidtype", ScalarType::Int32},
        {"unsigned_int", ScalarType::UInt32}, {"vtktypeuint32", ScalarType::UInt32},
        {"long", ScalarType::Int64}, {"long_long", ScalarType::Int64},
        {"vtktypeint64", ScalarType::Int64}, {"__int64", ScalarType::Int64},
        {"unsigned_long", ScalarType::UInt64}, {"unsigned_long_long", ScalarType::UInt64},
        {"vtktypeuint64", ScalarType::UInt64}, {"unsigned___int64", ScalarType::UInt64},
        {"float", ScalarType::Float32}, {"vtktypefloat32", ScalarType::Float32},
        {"double", ScalarType::Float64}, {"vtktypefloat64", ScalarType::Float64},
    };
    return findTypeName(kTable, name, /*ignoreCase=*/true, type);
}

/// VTK 5 writes names with spaces and other special characters as %XX.
std::string
decodeVtkName(std::string_view name)
{
    std::string result;
    for (size_t i = 0; i < name.size(); ++i) {
        if (name[i] == '%' && i + 2 < name.size()) {
            unsigned value = 0;
            const auto r = std::from_chars(name.data() + i + 1, name.data() + i + 3, value, 16);
            if (r.ec == std::errc() && r.ptr == name.data() + i + 3) {
                result += char(value);
                i += 2;
                continue;
            }
        }
        result += name[i];
    }
    return result;
}

namespace {


class VtkParser
{
public:
    VtkParser(ByteInput& input, const std::string& path, bool wantPolygons)
        : mInput(input), mPath(path), mWantPolygons(wantPolygons) {}

    /// Whether parse() reached a POLYGONS section header declaring at least one polygon (true
    /// even if the section's data then failed to decode), or one of no polygon in a file
    /// whose POINTS section holds none (an empty mesh).
    bool sawPolygons() const { return mSawPolygons || (mSawEmptyPolygons && mPointCount == 0); }

    VtkData parse()
    {
        readHeader();
        bool havePoints = false;
        for (;;) {
            mInput.skipSpace();
            if (mInput.atEnd()) break;
            mLine = mInput.line();
            const std::vector<std::string_view> words = splitWords(mLine);
            const std::string key = upper(words.at(0));  // skipSpace() made words non-empty

            if (key == "POINTS") {
                if (havePoints) fail(mPath, "second POINTS section in VTK file");
                readPoints(words);
                havePoints = true;
            } else if (key == "CELLS" || key == "VERTICES" || key == "LINES" ||
                       key == "POLYGONS" || key == "TRIANGLE_STRIPS") {
                readCells(key, words);
            } else if (key == "CELL_TYPES") {
                requireWords(words, 2);
                mReader->skip(count(words[1]), ScalarType::Int32, "CELL_TYPES section");
            } else if (key == "POINT_DATA" || key == "CELL_DATA") {
                requireWords(words, 2);
                mTupleCount = count(words[1]);
                mInPointData = (key == "POINT_DATA");
                mInCellData = !mInPointData;
                if (mInPointData && havePoints && mTupleCount != mData.points.size()) {
                    fail(mPath, "POINT_DATA count " + std::to_string(mTupleCount) +
                        " differs from POINTS count " + std::to_string(mData.points.size()));
                }
            } else if (key == "SCALARS") {
                requireAttributeSection(key);
                if (words.size() < 3 || words.size() > 4) badHeader();
                uint64_t components = 1;
                if (words.size() == 4) components = count(words[3]);
                if (components < 1 || components > uint64_t(kMaxFileComponents)) badHeader();
                const ScalarType type = dataType(words[2]);
                // The LOOKUP_TABLE line is optional from VTK 5; binary data never starts
                // with that word, so peeking is safe.
                mInput.skipLineStartingWith("LOOKUP_TABLE", !mReader->binary());
                readAttribute(key, words[1], type, int(components));
            } else if (key == "VECTORS" || key == "NORMALS") {
                requireAttributeSection(key);
                requireWords(words, 3);
                readAttribute(key, words[1], dataType(words[2]), 3);
            } else if (key == "TENSORS" || key == "TENSORS6") {
                requireAttributeSection(key);
                requireWords(words, 3);
                readAttribute(key, words[1], dataType(words[2]), key == "TENSORS" ? 9 : 6);
            } else if (key == "TEXTURE_COORDINATES") {
                requireAttributeSection(key);
                requireWords(words, 4);
                const uint64_t dim = count(words[2]);
                if (dim < 1 || dim > 3) badHeader();
                readAttribute(key, words[1], dataType(words[3]), int(dim));
            } else if (key == "COLOR_SCALARS") {
                requireAttributeSection(key);
                requireWords(words, 3);
                const uint64_t components = count(words[2]);
                if (components < 1 || components > uint64_t(kMaxFileComponents)) badHeader();
                // Binary color scalars are bytes, ASCII ones floats in [0,1].
                readAttribute(key, words[1],
                    mReader->binary() ? ScalarType::UInt8 : ScalarType::Float32,
                    int(components));
            } else if (key == "LOOKUP_TABLE") {
                requireWords(words, 3);
                const uint64_t entries = count(words[2]);
                if (entries > std::numeric_limits<uint64_t>::max() / 4) badHeader();
                mReader->skip(entries * 4,
                    mReader->binary() ? ScalarType::UInt8 : ScalarType::Float32,
                    "LOOKUP_TABLE section");
            } else if (key == "FIELD") {
                requireWords(words, 3);
                readField(count(words[2]));
            } else if (key == "METADATA") {
                skipMetadata();
            } else {
                fail(mPath, "unexpected '" + printable(words[0]) + "' in VTK file");
            }
        }
        if (!havePoints) fail(mPath, "missing POINTS section in VTK file");
        // POINT_DATA may precede POINTS; every array must still have one tuple per point.
        for (const NumericArray& array : mData.pointArrays) {
            const size_t tuples =
                array.bytes.size() / (scalarSize(array.type) * size_t(array.components));
            if (tuples != mData.points.size()) {
                fail(mPath, "POINT_DATA count " + std::to_string(tuples) +
                    " differs from POINTS count " + std::to_string(mData.points.size()));
            }
        }
        return std::move(mData);
    }

private:
    void readHeader()
    {
        const std::string first = mInput.line();
        if (first.compare(0, 14, "# vtk DataFile") != 0) {
            fail(mPath, "not a legacy VTK file: the first line must start with '# vtk DataFile'");
        }
        mInput.line();  // title, free text
        if (mInput.atEnd()) fail(mPath, "truncated VTK header");
        const std::string formatLine = mInput.line();
        const std::string_view format = trim(formatLine);
        bool binary = false;
        if (iequals(format, "BINARY")) {
            binary = true;
        } else if (!iequals(format, "ASCII")) {
            fail(mPath, "bad VTK file type '" + printable(format) + "'; expected ASCII or BINARY");
        }
        mReader.reset(new ValueReader(mInput, binary, /*bigEndian=*/true, mPath));

        mInput.skipSpace();
        if (mInput.atEnd()) fail(mPath, "truncated VTK header");
        mLine = mInput.line();
        const std::vector<std::string_view> words = splitWords(mLine);
        if (words.size() != 2 || !iequals(words[0], "DATASET")) {
            fail(mPath, "expected 'DATASET <type>' in VTK file, got '" + printable(mLine) + "'");
        }
        if (!iequals(words[1], "UNSTRUCTURED_GRID") && !iequals(words[1], "POLYDATA")) {
            fail(mPath, "unsupported VTK dataset '" + printable(words[1]) +
                "'; expected UNSTRUCTURED_GRID or POLYDATA");
        }
    }

    [[noreturn]] void badHeader() const
    {
        fail(mPath, "bad header '" + printable(mLine) + "' in VTK file");
    }

    void requireWords(const std::vector<std::string_view>& words, size_t n) const
    {
        if (words.size() != n) badHeader();
    }

    uint64_t count(std::string_view text) const
    {
        uint64_t value = 0;
        if (!parseCount(text, value)) badHeader();
        return value;
    }

    ScalarType dataType(std::string_view name) const
    {
        ScalarType type;
        if (!vtkScalarType(name, type)) {
            fail(mPath, "unsupported VTK data type '" + printable(name) + "'");
        }
        return type;
    }

    void requireAttributeSection(const std::string& key) const
    {
        if (!mInPointData && !mInCellData) {
            fail(mPath, key + " before POINT_DATA or CELL_DATA in VTK file");
        }
    }

    void readPoints(const std::vector<std::string_view>& words)
    {
        requireWords(words, 3);
        const uint64_t n = count(words[1]);
        const ScalarType type = dataType(words[2]);
        if (type != ScalarType::Float32 && type != ScalarType::Float64) {
            fail(mPath, "unsupported POINTS type '" + printable(words[2]) +
                "'; expected float or double");
        }
        if (n > std::numeric_limits<uint64_t>::max() / 3) fail(mPath, "truncated POINTS section");
        mReader->requireRoom(3 * n, type, "POINTS section");
        static_assert(sizeof(openvdb::Vec3f) == 12, "Vec3f must be three packed floats");
        requireMemoryForParticles(mPath, n, sizeof(openvdb::Vec3f));
        mData.points.resize(size_t(n));
        mPointCount = n;
        mReader->readFloats(size_t(3 * n), type, "POINTS section",
            reinterpret_cast<float*>(mData.points.data()));
    }

    /// Cell sections: VTK ≤ 4.2 stores "n size" then size ints (count, indices...);
    /// VTK 5 stores "nOffsets nConnectivity" then OFFSETS and CONNECTIVITY arrays.
    void readCells(const std::string& key, const std::vector<std::string_view>& words)
    {
        requireWords(words, 3);
        const uint64_t n = count(words[1]);
        const uint64_t size = count(words[2]);
        const bool keep = mWantPolygons && key == "POLYGONS";
        const std::string section = key + " section";
        // VTK 5 counts offsets, one more than the cells: "POLYGONS 1 0" holds none (review).
        const bool offsetsFollow = mInput.peekWord("OFFSETS");
        // A POLYGONS section of no polygon declares an empty mesh when there are no points
        // either (as writeMesh() writes one); next to particles it says nothing.
        if (key == "POLYGONS") mSawEmptyPolygons = true;
        if (n > (offsetsFollow ? 1u : 0u)) {
            if (key == "POLYGONS") mSawPolygons = true;
            const bool surface = key == "POLYGONS" || key == "LINES" || key == "TRIANGLE_STRIPS";
            if (surface && !keep) mData.skippedSections.push_back(section);
        }

        if (offsetsFollow) {
            mInput.skipSpace();
            mLine = mInput.line();
            const std::vector<std::string_view> offsetWords = splitWords(mLine);
            requireWords(offsetWords, 2);
            const ScalarType offsetType = dataType(offsetWords[1]);
            std::vector<unsigned char> offsetBytes;
            if (keep) mReader->read(n, offsetType, section, offsetBytes);
            else mReader->skip(n, offsetType, section);

            mInput.skipSpace();
            mLine = mInput.line();
            const std::vector<std::string_view> connWords = splitWords(mLine);
            if (connWords.size() != 2 || !iequals(connWords[0], "CONNECTIVITY")) badHeader();
            const ScalarType connType = dataType(connWords[1]);
            std::vector<unsigned char> connBytes;
            if (keep) mReader->read(size, connType, section, connBytes);
            else mReader->skip(size, connType, section);

            if (keep) {
                if (!isIntegerType(offsetType) || !isIntegerType(connType)) badHeader();
                const std::vector<int64_t> offsets =
                    toIntegers(offsetBytes, offsetType, mPath, section);
                const std::vector<int64_t> conn = toIntegers(connBytes, connType, mPath, section);
                for (size_t i = 0; i + 1 < offsets.size(); ++i) {
                    if (offsets[i] < 0 || offsets[i] > offsets[i + 1] ||
                        uint64_t(offsets[i + 1]) > conn.size()) {
                        fail(mPath, "bad OFFSETS in " + section);
                    }
                    for (int64_t j = offsets[i]; j < offsets[i + 1]; ++j) {
                        mData.polygons.indices.push_back(checkedIndex(conn[size_t(j)], mPath, section));
                    }
                    mData.polygons.offsets.push_back(mData.polygons.indices.size());
                }
            }
            return;
        }
        if (!keep) {
            mReader->skip(size, ScalarType::Int32, section);
            return;
        }
        std::vector<unsigned char> bytes;
        mReader->read(size, ScalarType::Int32, section, bytes);
        const std::vector<int64_t> values = toIntegers(bytes, ScalarType::Int32, mPath, section);
        size_t p = 0;
        for (uint64_t cell = 0; cell < n; ++cell) {
            if (p >= values.size() || values[p] < 0 ||
                uint64_t(values[p]) > values.size() - p - 1) {
                fail(mPath, "truncated " + section);
            }
            const size_t corners = size_t(values[p++]);
            for (size_t j = 0; j < corners; ++j) {
                mData.polygons.indices.push_back(checkedIndex(values[p++], mPath, section));
            }
            mData.polygons.offsets.push_back(mData.polygons.indices.size());
        }
    }

    void readAttribute(const std::string& kind, std::string_view name, ScalarType type,
                       int components)
    {
        NumericArray array;
        array.name = decodeVtkName(name);
        array.kind = kind;
        array.type = type;
        array.components = components;
        const std::string section = kind + " '" + printable(array.name) + "' section";
        if (mTupleCount > std::numeric_limits<uint64_t>::max() / uint64_t(components)) {
            fail(mPath, "truncated " + section);
        }
        const uint64_t values = mTupleCount * uint64_t(components);
        if (mInPointData) {
            mReader->read(values, type, section, array.bytes);
            mData.pointArrays.push_back(std::move(array));
        } else {
            mReader->skip(values, type, section);
        }
    }

    void readField(uint64_t arrayCount)
    {
        for (uint64_t i = 0; i < arrayCount; ++i) {
            mInput.skipSpace();
            if (mInput.atEnd()) fail(mPath, "truncated FIELD section");
            if (mInput.peekWord("METADATA")) {
                mInput.line();
                skipMetadata();
                mInput.skipSpace();
            }
            mLine = mInput.line();
            const std::vector<std::string_view> words = splitWords(mLine);
            if (words.size() == 1 && iequals(words[0], "NULL_ARRAY")) continue;
            requireWords(words, 4);
            const uint64_t components = count(words[1]);
            const uint64_t tuples = count(words[2]);
            const ScalarType type = dataType(words[3]);
            if (components < 1 || components > uint64_t(kMaxFileComponents)) badHeader();

            NumericArray array;
            array.name = decodeVtkName(words[0]);
            array.kind = "FIELD";
            array.type = type;
            array.components = int(components);
            const std::string section = "FIELD array '" + printable(array.name) + "'";
            if (tuples > std::numeric_limits<uint64_t>::max() / components) {
                fail(mPath, "truncated " + section);
            }
            if (mInPointData) {
                if (tuples != mTupleCount) {
                    fail(mPath, section + " has " + std::to_string(tuples) +
                        " tuples but POINT_DATA has " + std::to_string(mTupleCount));
                }
                mReader->read(tuples * components, type, section, array.bytes);
                mData.pointArrays.push_back(std::move(array));
            } else {
                mReader->skip(tuples * components, type, section);
            }
        }
    }

    /// A METADATA block (VTK 5) is text lines up to the first blank line.
    void skipMetadata()
    {
        while (!mInput.atEnd()) {
            if (trim(mInput.line()).empty()) break;
        }
    }

    ByteInput& mInput;
    const std::string& mPath;
    bool mWantPolygons;
    std::unique_ptr<ValueReader> mReader;
    std::string mLine;            ///< the header line being interpreted, for messages
    bool mInPointData = false;
    bool mInCellData = false;
    uint64_t mTupleCount = 0;
    VtkData mData;
    bool mSawPolygons = false;
    bool mSawEmptyPolygons = false;  ///< a POLYGONS section, maybe of no polygon
    uint64_t mPointCount = 0;        ///< of the POINTS section (parse() moves mData out)
};

} // namespace

VtkData
parseVtk(ByteInput& input, const std::string& path, bool wantPolygons)
{
    return VtkParser(input, path, wantPolygons).parse();
}

VtkData
parseVtk(const char* data, size_t size, const std::string& path, bool wantPolygons)
{
    Cursor cursor(data, size);
    return parseVtk(cursor, path, wantPolygons);
}

bool
vtkDeclaresPolygons(const char* data, size_t size, const std::string& path)
{
    Cursor cursor(data, size);
    VtkParser parser(cursor, path, /*wantPolygons=*/false);
    try {
        parser.parse();
    } catch (const FileError&) {
        // Broken before or after its POLYGONS header: what was seen until then decides.
    }
    return parser.sawPolygons();
}

// ------------------------------------------------------------------------------------------
// PLY

bool
plyScalarType(std::string_view name, ScalarType& type)
{
    static const TypeName kTable[] = {
        {"char", ScalarType::Int8}, {"int8", ScalarType::Int8},
        {"uchar", ScalarType::UInt8}, {"uint8", ScalarType::UInt8},
        {"short", ScalarType::Int16}, {"int16", ScalarType::Int16},
        {"ushort", ScalarType::UInt16}, {"uint16", ScalarType::UInt16},
        {"int", ScalarType::Int32}, {"int32", ScalarType::Int32},
        {"uint", ScalarType::UInt32}, {"uint32", ScalarType::UInt32},
        {"int64", ScalarType::Int64}, {"uint64", ScalarType::UInt64},
        {"float", ScalarType::Float32}, {"float32", ScalarType::Float32},
        {"double", ScalarType::Float64}, {"float64", ScalarType::Float64},
    };
    return findTypeName(kTable, name, /*ignoreCase=*/false, type);
}

void
PlyReaderBase::readHeader()
{
    if (trim(mInput.line()) != "ply") fail(mPath, "not a PLY file: the first line must be 'ply'");
    bool haveFormat = false;
    for (;;) {
        if (mInput.atEnd()) fail(mPath, "truncated PLY header: no end_header line");
        const std::string line = mInput.line();
        const std::vector<std::string_view> words = splitWords(line);
        if (words.empty()) continue;
        const std::string_view key = words[0];
        if (key == "end_header") break;
        if (key == "comment" || key == "obj_info") continue;
        if (key == "format") {
            if (words.size() != 3) badHeader(line);
            bool binary = true, bigEndian = false;
            if (words[1] == "ascii") binary = false;
            else if (words[1] == "binary_big_endian") bigEndian = true;
            else if (words[1] != "binary_little_endian") {
                fail(mPath, "unsupported PLY format '" + printable(words[1]) +
                    "'; expected ascii, binary_little_endian or binary_big_endian");
            }
            mReader.reset(new ValueReader(mInput, binary, bigEndian, mPath));
            haveFormat = true;
        } else if (key == "element") {
            if (words.size() != 3) badHeader(line);
            PlyElement element;
            element.name = std::string(words[1]);
            if (!parseCount(words[2], element.count)) badHeader(line);
            mElements.push_back(std::move(element));
        } else if (key == "property") {
            if (mElements.empty()) badHeader(line);
            PlyProperty property;
            if (words.size() == 5 && words[1] == "list") {
                property.isList = true;
                if (!plyScalarType(words[2], property.countType) ||
                    !plyScalarType(words[3], property.type) ||
                    !isIntegerType(property.countType)) badHeader(line);
                property.name = std::string(words[4]);
            } else if (words.size() == 3) {
                if (!plyScalarType(words[1], property.type)) badHeader(line);
                property.name = std::string(words[2]);
            } else {
                badHeader(line);
            }
            mElements.back().properties.push_back(std::move(property));
        } else {
            badHeader(line);
        }
    }
    if (!haveFormat) fail(mPath, "PLY header has no format line");
}

void
PlyReaderBase::badHeader(std::string_view line) const
{
    fail(mPath, "bad PLY header line '" + printable(line) + "'");
}

void
PlyReaderBase::requireRoom(const PlyElement& element, const std::string& section) const
{
    // Binary records need at least their scalars and list lengths; a text value at
    // least one character and a separator (the last one may lack it).
    uint64_t minRecord = 0;
    for (const PlyProperty& property : element.properties) {
        minRecord += mReader->binary()
            ? scalarSize(property.isList ? property.countType : property.type) : 2;
    }
    const uint64_t room = mInput.remaining() + (mReader->binary() ? 0 : 1);
    if (minRecord > 0 && element.count > room / minRecord) {
        fail(mPath, "truncated " + section);
    }
}

void
PlyReaderBase::requireAxes(const PlyElement& element) const
{
    for (const char* axis : {"x", "y", "z"}) {
        const auto found = std::find_if(element.properties.begin(), element.properties.end(),
            [axis](const PlyProperty& p) { return !p.isList && p.name == axis; });
        if (found == element.properties.end()) {
            fail(mPath, std::string("PLY vertex element has no '") + axis + "' property");
        }
    }
}

void
PlyReaderBase::skipList(const PlyProperty& property, const std::string& section)
{
    const int64_t n = mReader->readInteger(property.countType, section);
    if (n < 0) fail(mPath, "negative list length in " + section);
    mReader->skip(uint64_t(n), property.type, section);
}

void
PlyReaderBase::skipElement(const PlyElement& element)
{
    const std::string section = "PLY " + printable(element.name) + " element";
    if (element.properties.empty()) return;  // nothing stored, whatever the count
    requireRoom(element, section);
    bool fixedSize = mReader->binary();
    uint64_t recordSize = 0;
    for (const PlyProperty& property : element.properties) {
        fixedSize = fixedSize && !property.isList;
        recordSize += scalarSize(property.type);
    }
    if (fixedSize) {
        // requireRoom() checked count × recordSize against the bytes left.
        mReader->skip(element.count * recordSize, ScalarType::UInt8, section);
        return;
    }
    for (uint64_t i = 0; i < element.count; ++i) {
        for (const PlyProperty& property : element.properties) {
            if (property.isList) skipList(property, section);
            else mReader->skip(1, property.type, section);
        }
    }
}

namespace {

/// The vertex and face elements of a PLY file in memory, as plain arrays.
class PlyParser : public PlyReaderBase
{
public:
    PlyParser(ByteInput& input, const std::string& path, bool wantFaces)
        : PlyReaderBase(input, path), mWantFaces(wantFaces) {}

    PlyData parse()
    {
        readHeader();
        bool haveVertices = false, haveFaces = false;
        for (const PlyElement& element : mElements) {
            if (haveVertices && (haveFaces || !mWantFaces)) break;  // the rest is not needed
            if (element.name == "vertex" && !haveVertices) {
                readVertices(element);
                haveVertices = true;
            } else if (element.name == "face" && mWantFaces && !haveFaces) {
                readFaces(element);
                haveFaces = true;
            } else {
                skipElement(element);
            }
        }
        if (!haveVertices) fail(mPath, "PLY file has no vertex element");
        return std::move(mData);
    }

private:
    void readVertices(const PlyElement& element)
    {
        const std::string section = "PLY vertex element";
        requireAxes(element);
        requireRoom(element, section);
        mData.vertexCount = size_t(element.count);
        std::vector<NumericArray*> columns(element.properties.size(), nullptr);
        for (const PlyProperty& property : element.properties) {
            if (property.isList) continue;
            NumericArray array;
            array.name = property.name;
            array.kind = "PLY";
            array.type = property.type;
            array.components = 1;
            array.bytes.resize(mData.vertexCount * scalarSize(property.type));
            mData.vertexProperties.push_back(std::move(array));
        }
        for (size_t p = 0, column = 0; p < element.properties.size(); ++p) {
            if (!element.properties[p].isList) columns[p] = &mData.vertexProperties[column++];
        }
        for (size_t i = 0; i < mData.vertexCount; ++i) {
            for (size_t p = 0; p < element.properties.size(); ++p) {
                const PlyProperty& property = element.properties[p];
                if (property.isList) {
                    skipList(property, section);
                } else {
                    const size_t width = scalarSize(property.type);
                    mReader->readInto(1, property.type, section,
                        columns[p]->bytes.data() + i * width);
                }
            }
        }
    }

    void readFaces(const PlyElement& element)
    {
        const std::string section = "PLY face element";
        requireRoom(element, section);
        size_t indexProperty = element.properties.size();
        for (size_t p = 0; p < element.properties.size(); ++p) {
            const PlyProperty& property = element.properties[p];
            if (property.isList && (property.name == "vertex_indices" ||
                                    property.name == "vertex_index")) {
                indexProperty = p;
                break;
            }
        }
        if (indexProperty == element.properties.size()) {
            fail(mPath, "PLY face element has no vertex_indices list");
        }
        if (!isIntegerType(element.properties[indexProperty].type)) {
            fail(mPath, "PLY vertex_indices must be integers");
        }
        PolygonList& faces = mData.faces;
        faces.offsets.reserve(size_t(element.count) + 1);
        unsigned char bytes[8];
        for (uint64_t i = 0; i < element.count; ++i) {
            for (size_t p = 0; p < element.properties.size(); ++p) {
                const PlyProperty& property = element.properties[p];
                if (p != indexProperty) {
                    if (property.isList) skipList(property, section);
                    else mReader->skip(1, property.type, section);
                    continue;
                }
                const int64_t n = mReader->readInteger(property.countType, section);
                if (n < 0) fail(mPath, "negative list length in " + section);
                mReader->requireRoom(uint64_t(n), property.type, section);
                for (int64_t j = 0; j < n; ++j) {
                    mReader->readInto(1, property.type, section, bytes);
                    int64_t index = 0;
                    if (!integerValue(bytes, property.type, index)) {
                        fail(mPath, "integer out of range in " + section);
                    }
                    faces.indices.push_back(checkedIndex(index, mPath, section));
                }
                faces.offsets.push_back(faces.indices.size());
            }
        }
    }

    bool mWantFaces;
    PlyData mData;
};

} // namespace

PlyData
parsePly(const char* data, size_t size, const std::string& path, bool wantFaces)
{
    Cursor cursor(data, size);
    return PlyParser(cursor, path, wantFaces).parse();
}

namespace {

/// Reads a PLY header and nothing else.
class PlyHeaderReader : public PlyReaderBase
{
public:
    PlyHeaderReader(ByteInput& input, const std::string& path) : PlyReaderBase(input, path) {}

    bool declaresFaces()
    {
        readHeader();
        bool faceElement = false;
        uint64_t vertices = 0;
        for (const PlyElement& element : mElements) {
            if (element.name == "face" && element.count > 0) return true;
            if (element.name == "face") faceElement = true;
            if (element.name == "vertex") vertices = element.count;
        }
        // An empty face element with vertices is a point cloud (MeshLab writes them so);
        // without vertices, an empty mesh (as writeMesh() writes one).
        return faceElement && vertices == 0;
    }
};

} // namespace

bool
plyDeclaresFaces(const char* data, size_t size, const std::string& path)
{
    Cursor cursor(data, size);
    try {
        return PlyHeaderReader(cursor, path).declaresFaces();
    } catch (const FileError&) {
        return false;  // no readable header: not a mesh by declaration
    }
}

} // namespace io_internal
} // namespace nonbloppy
