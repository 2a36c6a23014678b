// SPDX-License-Identifier: Apache-2.0
/// @file ReadParticles.cc
/// @brief Stage "read particles": legacy VTK, PLY and raw XYZ files streamed from the file
///        straight into the final arrays; the other formats through ParticleReaders.h.
///
/// The VTK, PLY and XYZ readers never hold the whole file: a FileStream reads it in chunks
/// of kChunkBytes, and large binary arrays (positions, attributes) are read with read(2)
/// directly into the ParticleSet's vectors, then byte-swapped in place if needed. Peak
/// memory is the ParticleSet plus one chunk. Every count in a header is still checked
/// against the bytes left in the file (its size from fstat) before anything is allocated.
/// Pipes and other non-regular files, whose size is unknown, are loaded whole first.
///
/// Messages are word for word those of FileFormats.cc's parsers, which readMesh() and the
/// fuzz targets keep using.

#include <nonbloppy/ReadParticles.h>

#include <nonbloppy/Error.h>

#include "FileFormats.h"
#include "ParticleReaders.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace nonbloppy {

namespace {

using namespace io_internal;

/// Bytes read from the file at a time (the buffer grows beyond it only for a single
/// header line or text token longer than that).
constexpr size_t kChunkBytes = size_t(1) << 20;

constexpr bool kHostIsBigEndian = (__BYTE_ORDER__ == __ORDER_BIG_ENDIAN__);

// ------------------------------------------------------------------------------------------
// Text helpers (as in FileFormats.cc)

bool
isSpace(char ch)
{
    return ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r' || ch == '\v' || ch == '\f';
}

char
toLower(char ch)
{
    return (ch >= 'A' && ch <= 'Z') ? char(ch - 'A' + 'a') : ch;
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

bool
parseCount(std::string_view text, uint64_t& value)
{
    const char* end = text.data() + text.size();
    const auto result = std::from_chars(text.data(), end, value);
    return !text.empty() && result.ec == std::errc() && result.ptr == end;
}

bool
parseDouble(std::string_view text, double& value)
{
    if (!text.empty() && text.front() == '+') text.remove_prefix(1);
    if (text.empty()) return false;
    const char* end = text.data() + text.size();
    const auto result = std::from_chars(text.data(), end, value);
    if (result.ec == std::errc() && result.ptr == end) return true;
    if (result.ec == std::errc::result_out_of_range && text.size() < 64) {
        // from_chars leaves the value unset for 1e-400 or 1e400; strtod gives 0 or inf.
        const std::string copy(text);
        char* parsedEnd = nullptr;
        value = std::strtod(copy.c_str(), &parsedEnd);
        return parsedEnd == copy.c_str() + copy.size();
    }
    return false;
}

template<typename IntT>
bool
parseInteger(std::string_view text, IntT& value)
{
    if (!text.empty() && text.front() == '+') text.remove_prefix(1);
    const char* end = text.data() + text.size();
    const auto result = std::from_chars(text.data(), end, value);
    return !text.empty() && result.ec == std::errc() && result.ptr == end;
}

template<typename IntT, typename WideT>
bool
parseNarrow(std::string_view text, unsigned char* out)
{
    WideT wide;
    if (!parseInteger(text, wide)) return false;
    if (wide < WideT(std::numeric_limits<IntT>::min()) ||
        wide > WideT(std::numeric_limits<IntT>::max())) return false;
    const IntT value = IntT(wide);
    std::memcpy(out, &value, sizeof(IntT));
    return true;
}

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

/// Reverse the bytes of each of @a count values of @a width bytes at @a data.
void
swapInPlace(unsigned char* data, size_t count, size_t width)
{
    switch (width) {
        case 2:
            for (size_t i = 0; i < count; ++i) {
                uint16_t v;
                std::memcpy(&v, data + 2 * i, 2);
                v = __builtin_bswap16(v);
                std::memcpy(data + 2 * i, &v, 2);
            }
            break;
        case 4:
            for (size_t i = 0; i < count; ++i) {
                uint32_t v;
                std::memcpy(&v, data + 4 * i, 4);
                v = __builtin_bswap32(v);
                std::memcpy(data + 4 * i, &v, 4);
            }
            break;
        case 8:
            for (size_t i = 0; i < count; ++i) {
                uint64_t v;
                std::memcpy(&v, data + 8 * i, 8);
                v = __builtin_bswap64(v);
                std::memcpy(data + 8 * i, &v, 8);
            }
            break;
        default: break;
    }
}

bool
isIntegerType(ScalarType type)
{
    return type != ScalarType::Float32 && type != ScalarType::Float64;
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

/// A native Float32 or Float64 value at @a p as float (positions are stored as float).
float
floatValue(const unsigned char* p, ScalarType type)
{
    if (type == ScalarType::Float32) {
        float v;
        std::memcpy(&v, p, 4);
        return v;
    }
    double v;
    std::memcpy(&v, p, 8);
    return float(v);
}

// ------------------------------------------------------------------------------------------
// FileStream

/// A read position in a file, with a bounded buffer of the bytes just ahead of it.
/// Text access (tokens, lines) goes through the buffer; readBytes() copies large binary
/// blocks straight from the file into the caller's memory.
class FileStream
{
public:
    explicit FileStream(const std::string& path) : mPath(path)
    {
        mFd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
        if (mFd < 0) throw FileError("cannot open " + path + ": " + std::strerror(errno));
        struct stat info;
        if (::fstat(mFd, &info) != 0) {
            const int error = errno;
            closeFile();
            throw readError(error);
        }
        if (S_ISDIR(info.st_mode)) {
            closeFile();
            throw readError(EISDIR);
        }
        if (S_ISREG(info.st_mode)) {
            mSize = uint64_t(info.st_size);
            mBuffer.resize(size_t(std::min<uint64_t>(kChunkBytes, std::max<uint64_t>(mSize, 64))));
        } else {
            // st_size means nothing for pipes and /proc files: hold the whole contents.
            closeFile();
            mBuffer = loadFile(path);
            mTail = mBuffer.size();
            mSize = mTail;
            mEof = true;
        }
    }
    ~FileStream() { closeFile(); }
    FileStream(const FileStream&) = delete;
    FileStream& operator=(const FileStream&) = delete;

    uint64_t size() const { return mSize; }
    uint64_t pos() const { return mBufferStart + mHead; }
    uint64_t remaining() const { return mSize - pos(); }
    bool atEnd() { return !ensure(1); }
    const char* here() const { return mBuffer.data() + mHead; }
    size_t available() const { return mTail - mHead; }
    void advance(size_t n) { mHead += std::min(n, available()); }

    /// True once at least @a n bytes are buffered at here(); false if the file ends first.
    bool ensure(size_t n)
    {
        while (available() < n) {
            if (!fill()) return false;
        }
        return true;
    }

    /// Copy the next @a n bytes into @a dst; false (having moved to the end) if the file
    /// ends first. Beyond what is buffered, reads go straight from the file into @a dst.
    bool readBytes(unsigned char* dst, size_t n)
    {
        const size_t buffered = std::min(n, available());
        if (buffered > 0) std::memcpy(dst, here(), buffered);
        mHead += buffered;
        dst += buffered;
        n -= buffered;
        if (n == 0) return true;
        if (n < mBuffer.size() / 2) {
            if (!ensure(n)) {
                mHead = mTail;
                return false;
            }
            std::memcpy(dst, here(), n);
            mHead += n;
            return true;
        }
        // Buffer empty: read directly.
        mBufferStart = pos();
        mHead = mTail = 0;
        while (n > 0) {
            const uint64_t fileLeft = mSize - mBufferStart;
            const size_t want = size_t(std::min<uint64_t>(n, fileLeft));
            if (want == 0) {
                mEof = true;
                return false;
            }
            const ssize_t got = ::read(mFd, dst, want);
            if (got < 0) {
                if (errno == EINTR) continue;
                throw readError(errno);
            }
            if (got == 0) {
                mSize = mBufferStart;  // the file shrank since fstat
                mEof = true;
                return false;
            }
            dst += got;
            n -= size_t(got);
            mBufferStart += uint64_t(got);
        }
        return true;
    }

    /// Move @a n bytes ahead (callers check remaining() first).
    void skipBytes(uint64_t n)
    {
        const uint64_t target = std::min(pos() + n, mSize);
        if (target <= mBufferStart + mTail) {
            mHead = size_t(target - mBufferStart);
            return;
        }
        mBufferStart = target;
        mHead = mTail = 0;
        if (::lseek(mFd, off_t(target), SEEK_SET) < 0) throw readError(errno);
    }

    void skipSpace()
    {
        for (;;) {
            while (mHead < mTail && isSpace(mBuffer[mHead])) ++mHead;
            if (mHead < mTail || !fill()) return;
        }
    }

    /// The next run of non-space characters (empty at the end of the file). The view is
    /// valid until the next call on this stream.
    std::string_view token()
    {
        skipSpace();
        size_t length = 0;
        for (;;) {
            while (mHead + length < mTail && !isSpace(mBuffer[mHead + length])) ++length;
            if (mHead + length < mTail || !fill()) break;
        }
        const std::string_view text(mBuffer.data() + mHead, length);
        mHead += length;
        return text;
    }

    /// The rest of the current line without its line break; moves past the '\n'.
    std::string line()
    {
        size_t length = 0;
        bool found = false;
        for (;;) {
            const void* newline =
                std::memchr(mBuffer.data() + mHead + length, '\n', mTail - mHead - length);
            if (newline) {
                length = size_t(static_cast<const char*>(newline) - (mBuffer.data() + mHead));
                found = true;
                break;
            }
            length = mTail - mHead;
            if (!fill()) break;
        }
        size_t end = length;
        if (end > 0 && mBuffer[mHead + end - 1] == '\r') --end;
        std::string text(mBuffer.data() + mHead, end);
        mHead += length + (found ? 1 : 0);
        return text;
    }

    /// True if the next non-space text is the word @a word (case-insensitive). Moves nothing.
    bool peekWord(std::string_view word)
    {
        size_t i = 0;
        for (;; ++i) {
            if (!ensure(i + 1)) return false;
            if (!isSpace(here()[i])) break;
        }
        for (size_t j = 0; j < word.size(); ++j) {
            if (!ensure(i + j + 1) || toLower(here()[i + j]) != toLower(word[j])) return false;
        }
        return !ensure(i + word.size() + 1) || isSpace(here()[i + word.size()]);
    }

private:
    FileError readError(int errorNumber) const
    {
        return FileError("cannot read " + mPath + ": " + std::strerror(errorNumber));
    }

    void closeFile()
    {
        if (mFd >= 0) ::close(mFd);
        mFd = -1;
    }

    /// Read more of the file behind the buffered bytes; false at the end of the file.
    bool fill()
    {
        if (mEof) return false;
        if (mHead > 0) {
            std::memmove(mBuffer.data(), mBuffer.data() + mHead, mTail - mHead);
            mBufferStart += mHead;
            mTail -= mHead;
            mHead = 0;
        }
        if (mTail == mBuffer.size()) mBuffer.resize(mBuffer.size() * 2);
        const uint64_t fileLeft = mSize - (mBufferStart + mTail);
        const size_t want = size_t(std::min<uint64_t>(mBuffer.size() - mTail, fileLeft));
        if (want == 0) {
            mEof = true;
            return false;
        }
        for (;;) {
            const ssize_t got = ::read(mFd, mBuffer.data() + mTail, want);
            if (got < 0) {
                if (errno == EINTR) continue;
                throw readError(errno);
            }
            if (got == 0) {
                mSize = mBufferStart + mTail;  // the file shrank since fstat
                mEof = true;
                return false;
            }
            mTail += size_t(got);
            return true;
        }
    }

    const std::string& mPath;
    int mFd = -1;
    std::vector<char> mBuffer;
    size_t mHead = 0, mTail = 0;   ///< the unread buffered bytes are mBuffer[mHead, mTail)
    uint64_t mBufferStart = 0;     ///< file offset of mBuffer[0]
    uint64_t mSize = 0;            ///< file size
    bool mEof = false;
};

/// Reads typed value arrays from a FileStream, text or binary, never past the file's end.
class ValueReader
{
public:
    ValueReader(FileStream& stream, bool binary, bool bigEndian, const std::string& path)
        : mStream(stream), mBinary(binary), mSwap(binary && bigEndian != kHostIsBigEndian)
        , mPath(path) {}

    bool binary() const { return mBinary; }
    bool swaps() const { return mSwap; }

    /// Fail with "truncated <section> (path)" unless @a count values of @a type can still
    /// be in the file: checked before allocating, so a corrupt count cannot exhaust memory.
    void requireRoom(uint64_t count, ScalarType type, const std::string& section) const
    {
        const uint64_t left = mStream.remaining();
        // A text value takes at least one character plus a separator.
        const uint64_t capacity = mBinary ? left / scalarSize(type) : (left + 1) / 2;
        if (count > capacity) fail(mPath, "truncated " + section);
    }

    /// @a count values of @a type, in native byte order, into @a dst (room for
    /// count × scalarSize(type) bytes).
    void readInto(size_t count, ScalarType type, const std::string& section,
                  unsigned char* dst)
    {
        requireRoom(count, type, section);
        const size_t width = scalarSize(type);
        if (mBinary) {
            if (!mStream.readBytes(dst, count * width)) fail(mPath, "truncated " + section);
            if (mSwap && width > 1) swapInPlace(dst, count, width);
            return;
        }
        for (size_t i = 0; i < count; ++i) readText(type, section, dst + i * width);
    }

    /// One text value of @a type into @a dst.
    void readText(ScalarType type, const std::string& section, unsigned char* dst)
    {
        const std::string_view text = mStream.token();
        if (text.empty()) fail(mPath, "truncated " + section);
        if (!parseTextValue(text, type, dst)) {
            fail(mPath, "bad " + std::string(scalarTypeName(type)) + " value '" +
                printable(text) + "' in " + section);
        }
    }

    /// @a count Float32 or Float64 values as floats into @a dst; doubles go through a
    /// bounded buffer.
    void readFloats(size_t count, ScalarType type, const std::string& section, float* dst)
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

    /// Move past @a count values of @a type without keeping them.
    void skip(uint64_t count, ScalarType type, const std::string& section)
    {
        requireRoom(count, type, section);
        if (mBinary) {
            mStream.skipBytes(count * scalarSize(type));
            return;
        }
        for (uint64_t i = 0; i < count; ++i) {
            if (mStream.token().empty()) fail(mPath, "truncated " + section);
        }
    }

    /// One value of integer @a type (e.g. a PLY list length).
    int64_t readInteger(ScalarType type, const std::string& section)
    {
        unsigned char bytes[8];
        readInto(1, type, section, bytes);
        int64_t value = 0;
        if (!integerValue(bytes, type, value)) fail(mPath, "integer out of range in " + section);
        return value;
    }

private:
    FileStream& mStream;
    bool mBinary;
    bool mSwap;
    const std::string& mPath;
};

// ------------------------------------------------------------------------------------------
// Legacy VTK

bool
vtkScalarType(std::string_view name, ScalarType& type)
{
    struct Entry { const char* name; ScalarType type; };
    // "long" is 8 bytes as VTK writes it on Linux/macOS; VTK's legacy writer stores
    // vtkIdType arrays as 32-bit int for backward compatibility.
    static const Entry kTable[] = {
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
    for (const Entry& entry : kTable) {
        if (iequals(name, entry.name)) {
            type = entry.type;
            return true;
        }
    }
    return false;
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

/// The particle part of a legacy VTK file: POINTS and the POINT_DATA arrays, read straight
/// into a ParticleSet; cells, CELL_DATA, lookup tables and METADATA are skipped.
class VtkReader
{
public:
    VtkReader(const std::string& path) : mStream(path), mPath(path) {}

    ParticleSet read()
    {
        readHeader();
        bool havePoints = false;
        for (;;) {
            mStream.skipSpace();
            if (mStream.atEnd()) break;
            mLine = mStream.line();
            const std::vector<std::string_view> words = splitWords(mLine);
            const std::string key = upper(words.at(0));  // skipSpace() made words non-empty

            if (key == "POINTS") {
                if (havePoints) fail(mPath, "second POINTS section in VTK file");
                readPoints(words);
                havePoints = true;
            } else if (key == "CELLS" || key == "VERTICES" || key == "LINES" ||
                       key == "POLYGONS" || key == "TRIANGLE_STRIPS") {
                skipCells(key, words);
            } else if (key == "CELL_TYPES") {
                requireWords(words, 2);
                mReader->skip(count(words[1]), ScalarType::Int32, "CELL_TYPES section");
            } else if (key == "POINT_DATA" || key == "CELL_DATA") {
                requireWords(words, 2);
                mTupleCount = count(words[1]);
                mInPointData = (key == "POINT_DATA");
                mInCellData = !mInPointData;
                if (mInPointData && havePoints && mTupleCount != mData.positions.size()) {
                    fail(mPath, "POINT_DATA count " + std::to_string(mTupleCount) +
                        " differs from POINTS count " + std::to_string(mData.positions.size()));
                }
            } else if (key == "SCALARS") {
                requireAttributeSection(key);
                if (words.size() < 3 || words.size() > 4) badHeader();
                uint64_t components = 1;
                if (words.size() == 4) components = count(words[3]);
                if (components < 1 || components > 4096) badHeader();
                const ScalarType type = dataType(words[2]);
                // The LOOKUP_TABLE line is optional from VTK 5; binary data never starts
                // with that word, so peeking is safe. Text values skip blanks anyway.
                if (!mReader->binary()) mStream.skipSpace();
                if (mStream.remaining() >= 12 && mStream.ensure(12) &&
                    iequals(std::string_view(mStream.here(), 12), "LOOKUP_TABLE")) {
                    mStream.line();
                }
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
                if (components < 1 || components > 4096) badHeader();
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
        for (const ParticleAttribute& attribute : mData.attributes) {
            const size_t tuples = attribute.bytes.size() /
                (scalarSize(attribute.type) * size_t(attribute.components));
            if (tuples != mData.positions.size()) {
                fail(mPath, "POINT_DATA count " + std::to_string(tuples) +
                    " differs from POINTS count " + std::to_string(mData.positions.size()));
            }
        }
        return std::move(mData);
    }

private:
    void readHeader()
    {
        const std::string first = mStream.line();
        if (first.compare(0, 14, "# vtk DataFile") != 0) {
            fail(mPath, "not a legacy VTK file: the first line must start with '# vtk DataFile'");
        }
        mStream.line();  // title, free text
        if (mStream.atEnd()) fail(mPath, "truncated VTK header");
        const std::string formatLine = mStream.line();
        const std::string_view format = trim(formatLine);
        bool binary = false;
        if (iequals(format, "BINARY")) {
            binary = true;
        } else if (!iequals(format, "ASCII")) {
            fail(mPath, "bad VTK file type '" + printable(format) + "'; expected ASCII or BINARY");
        }
        mReader.reset(new ValueReader(mStream, binary, /*bigEndian=*/true, mPath));

        mStream.skipSpace();
        if (mStream.atEnd()) fail(mPath, "truncated VTK header");
        mLine = mStream.line();
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
        mData.positions.resize(size_t(n));
        mReader->readFloats(size_t(3 * n), type, "POINTS section",
            reinterpret_cast<float*>(mData.positions.data()));
    }

    /// Cell sections: VTK ≤ 4.2 stores "n size" then size ints (count, indices...);
    /// VTK 5 stores "nOffsets nConnectivity" then OFFSETS and CONNECTIVITY arrays.
    void skipCells(const std::string& key, const std::vector<std::string_view>& words)
    {
        requireWords(words, 3);
        const uint64_t n = count(words[1]);
        const uint64_t size = count(words[2]);
        const std::string section = key + " section";

        if (mStream.peekWord("OFFSETS")) {
            mStream.skipSpace();
            mLine = mStream.line();
            const std::vector<std::string_view> offsetWords = splitWords(mLine);
            requireWords(offsetWords, 2);
            mReader->skip(n, dataType(offsetWords[1]), section);

            mStream.skipSpace();
            mLine = mStream.line();
            const std::vector<std::string_view> connWords = splitWords(mLine);
            if (connWords.size() != 2 || !iequals(connWords[0], "CONNECTIVITY")) badHeader();
            mReader->skip(size, dataType(connWords[1]), section);
            return;
        }
        mReader->skip(size, ScalarType::Int32, section);
    }

    void readAttribute(const std::string& kind, std::string_view name, ScalarType type,
                       int components)
    {
        ParticleAttribute attribute;
        attribute.name = decodeVtkName(name);
        attribute.type = type;
        attribute.components = components;
        const std::string section = kind + " '" + printable(attribute.name) + "' section";
        if (mTupleCount > std::numeric_limits<uint64_t>::max() / uint64_t(components)) {
            fail(mPath, "truncated " + section);
        }
        const uint64_t values = mTupleCount * uint64_t(components);
        if (mInPointData) {
            readValues(values, type, section, attribute.bytes);
            mData.attributes.push_back(std::move(attribute));
        } else {
            mReader->skip(values, type, section);
        }
    }

    /// @a count values into @a bytes, allocated only once the file can hold them.
    void readValues(uint64_t count, ScalarType type, const std::string& section,
                    std::vector<unsigned char>& bytes)
    {
        mReader->requireRoom(count, type, section);
        bytes.resize(size_t(count) * scalarSize(type));
        mReader->readInto(size_t(count), type, section, bytes.data());
    }

    void readField(uint64_t arrayCount)
    {
        for (uint64_t i = 0; i < arrayCount; ++i) {
            mStream.skipSpace();
            if (mStream.atEnd()) fail(mPath, "truncated FIELD section");
            if (mStream.peekWord("METADATA")) {
                mStream.line();
                skipMetadata();
                mStream.skipSpace();
            }
            mLine = mStream.line();
            const std::vector<std::string_view> words = splitWords(mLine);
            if (words.size() == 1 && iequals(words[0], "NULL_ARRAY")) continue;
            requireWords(words, 4);
            const uint64_t components = count(words[1]);
            const uint64_t tuples = count(words[2]);
            const ScalarType type = dataType(words[3]);
            if (components < 1 || components > 4096) badHeader();

            ParticleAttribute attribute;
            attribute.name = decodeVtkName(words[0]);
            attribute.type = type;
            attribute.components = int(components);
            const std::string section = "FIELD array '" + printable(attribute.name) + "'";
            if (tuples > std::numeric_limits<uint64_t>::max() / components) {
                fail(mPath, "truncated " + section);
            }
            if (mInPointData) {
                if (tuples != mTupleCount) {
                    fail(mPath, section + " has " + std::to_string(tuples) +
                        " tuples but POINT_DATA has " + std::to_string(mTupleCount));
                }
                readValues(tuples * components, type, section, attribute.bytes);
                mData.attributes.push_back(std::move(attribute));
            } else {
                mReader->skip(tuples * components, type, section);
            }
        }
    }

    /// A METADATA block (VTK 5) is text lines up to the first blank line.
    void skipMetadata()
    {
        while (!mStream.atEnd()) {
            if (trim(mStream.line()).empty()) break;
        }
    }

    FileStream mStream;
    const std::string& mPath;
    std::unique_ptr<ValueReader> mReader;
    std::string mLine;            ///< the header line being interpreted, for messages
    bool mInPointData = false;
    bool mInCellData = false;
    uint64_t mTupleCount = 0;
    ParticleSet mData;
};

// ------------------------------------------------------------------------------------------
// PLY

bool
plyScalarType(std::string_view name, ScalarType& type)
{
    struct Entry { const char* name; ScalarType type; };
    static const Entry kTable[] = {
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
    for (const Entry& entry : kTable) {
        if (name == entry.name) {
            type = entry.type;
            return true;
        }
    }
    return false;
}

struct PlyProperty
{
    std::string name;
    ScalarType type = ScalarType::Float32;   ///< value type (of the items, for lists)
    bool isList = false;
    ScalarType countType = ScalarType::UInt8;
};

struct PlyElement
{
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

/// Where one vertex property goes: a position axis, an attribute, or nowhere (lists).
struct PlyColumn
{
    int axis = -1;                      ///< 0, 1, 2 for x, y, z
    ParticleAttribute* attribute = nullptr;
    size_t width = 0;                   ///< bytes per value
};

/// The vertex element of a PLY file, read straight into a ParticleSet: x, y, z as
/// positions, every other scalar property as a 1-component attribute.
class PlyReader
{
public:
    PlyReader(const std::string& path) : mStream(path), mPath(path) {}

    ParticleSet read()
    {
        readHeader();
        for (const PlyElement& element : mElements) {
            if (element.name == "vertex") {
                readVertices(element);
                return std::move(mData);  // the rest of the file is not needed
            }
            skipElement(element);
        }
        fail(mPath, "PLY file has no vertex element");
    }

private:
    void readHeader()
    {
        if (trim(mStream.line()) != "ply") fail(mPath, "not a PLY file: the first line must be 'ply'");
        bool haveFormat = false;
        for (;;) {
            if (mStream.atEnd()) fail(mPath, "truncated PLY header: no end_header line");
            const std::string line = mStream.line();
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
                mReader.reset(new ValueReader(mStream, binary, bigEndian, mPath));
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

    [[noreturn]] void badHeader(std::string_view line) const
    {
        fail(mPath, "bad PLY header line '" + printable(line) + "'");
    }

    /// Fail unless @a element's records can fit in the bytes left (before allocating).
    void requireRoom(const PlyElement& element, const std::string& section) const
    {
        // Binary records need at least their scalars and list lengths; a text value at
        // least one character and a separator (the last one may lack it).
        uint64_t minRecord = 0;
        for (const PlyProperty& property : element.properties) {
            minRecord += mReader->binary()
                ? scalarSize(property.isList ? property.countType : property.type) : 2;
        }
        const uint64_t room = mStream.remaining() + (mReader->binary() ? 0 : 1);
        if (minRecord > 0 && element.count > room / minRecord) {
            fail(mPath, "truncated " + section);
        }
    }

    void skipList(const PlyProperty& property, const std::string& section)
    {
        const int64_t n = mReader->readInteger(property.countType, section);
        if (n < 0) fail(mPath, "negative list length in " + section);
        mReader->skip(uint64_t(n), property.type, section);
    }

    void readVertices(const PlyElement& element)
    {
        const std::string section = "PLY vertex element";
        for (const char* axis : {"x", "y", "z"}) {
            const auto found = std::find_if(element.properties.begin(), element.properties.end(),
                [axis](const PlyProperty& p) { return !p.isList && p.name == axis; });
            if (found == element.properties.end()) {
                fail(mPath, std::string("PLY vertex element has no '") + axis + "' property");
            }
        }
        requireRoom(element, section);
        const size_t count = size_t(element.count);

        // Lay out the destinations first: positions and one attribute per other scalar.
        size_t attributeCount = 0;
        for (const PlyProperty& property : element.properties) {
            if (property.isList) continue;
            const int axis = axisOf(property.name);
            if (axis < 0) {
                ++attributeCount;
            } else if (property.type != ScalarType::Float32 &&
                       property.type != ScalarType::Float64) {
                fail(mPath, "PLY property '" + property.name + "' must be float or double");
            }
        }
        mData.positions.resize(count);
        mData.attributes.reserve(attributeCount);  // the columns point into it
        std::vector<PlyColumn> columns(element.properties.size());
        for (size_t p = 0; p < element.properties.size(); ++p) {
            const PlyProperty& property = element.properties[p];
            if (property.isList) continue;
            PlyColumn& column = columns[p];
            column.width = scalarSize(property.type);
            column.axis = axisOf(property.name);
            if (column.axis >= 0) continue;
            ParticleAttribute attribute;
            attribute.name = property.name;
            attribute.type = property.type;
            attribute.components = 1;
            attribute.bytes.resize(count * column.width);
            mData.attributes.push_back(std::move(attribute));
            column.attribute = &mData.attributes.back();
        }

        bool hasList = false;
        for (const PlyProperty& property : element.properties) hasList = hasList || property.isList;
        if (isPackedFloatXyz(element)) {
            // x y z float and nothing else: the file's bytes are the position array's.
            mReader->readInto(3 * count, ScalarType::Float32, section,
                reinterpret_cast<unsigned char*>(mData.positions.data()));
        } else if (mReader->binary() && !hasList) {
            readFixedRecords(element, columns, section);
        } else {
            readRecordByRecord(element, columns, section);
        }
    }

    static int axisOf(const std::string& name)
    {
        return name == "x" ? 0 : name == "y" ? 1 : name == "z" ? 2 : -1;
    }

    bool isPackedFloatXyz(const PlyElement& element) const
    {
        const std::vector<PlyProperty>& p = element.properties;
        return mReader->binary() && p.size() == 3 && p[0].name == "x" && p[1].name == "y" &&
            p[2].name == "z" && !p[0].isList && !p[1].isList && !p[2].isList &&
            p[0].type == ScalarType::Float32 && p[1].type == ScalarType::Float32 &&
            p[2].type == ScalarType::Float32;
    }

    /// Binary records of one size: decoded a buffered block of whole records at a time.
    void readFixedRecords(const PlyElement& element, const std::vector<PlyColumn>& columns,
                          const std::string& section)
    {
        size_t recordSize = 0;
        for (const PlyColumn& column : columns) recordSize += column.width;
        const bool swap = mReader->swaps();
        const size_t count = size_t(element.count);
        for (size_t i = 0; i < count;) {
            if (!mStream.ensure(recordSize)) fail(mPath, "truncated " + section);
            const size_t block = std::min(count - i, mStream.available() / recordSize);
            const unsigned char* record = reinterpret_cast<const unsigned char*>(mStream.here());
            for (size_t r = 0; r < block; ++r, ++i) {
                for (size_t p = 0; p < columns.size(); ++p) {
                    const PlyColumn& column = columns[p];
                    unsigned char value[8];
                    std::memcpy(value, record, column.width);
                    if (swap && column.width > 1) swapInPlace(value, 1, column.width);
                    if (column.axis >= 0) {
                        mData.positions[i][column.axis] =
                            floatValue(value, element.properties[p].type);
                    } else {
                        std::memcpy(column.attribute->bytes.data() + i * column.width, value,
                                    column.width);
                    }
                    record += column.width;
                }
            }
            mStream.advance(block * recordSize);
        }
    }

    /// Text records, or binary ones with list properties: one value at a time.
    void readRecordByRecord(const PlyElement& element, const std::vector<PlyColumn>& columns,
                            const std::string& section)
    {
        const size_t count = size_t(element.count);
        for (size_t i = 0; i < count; ++i) {
            for (size_t p = 0; p < element.properties.size(); ++p) {
                const PlyProperty& property = element.properties[p];
                const PlyColumn& column = columns[p];
                if (property.isList) {
                    skipList(property, section);
                } else if (column.axis >= 0) {
                    unsigned char value[8];
                    mReader->readInto(1, property.type, section, value);
                    mData.positions[i][column.axis] = floatValue(value, property.type);
                } else {
                    mReader->readInto(1, property.type, section,
                        column.attribute->bytes.data() + i * column.width);
                }
            }
        }
    }

    void skipElement(const PlyElement& element)
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

    FileStream mStream;
    const std::string& mPath;
    std::unique_ptr<ValueReader> mReader;
    std::vector<PlyElement> mElements;
    ParticleSet mData;
};

// ------------------------------------------------------------------------------------------
// XYZ

ParticleSet
readXyzParticles(const std::string& path)
{
    FileStream stream(path);
    if (stream.size() % 12 != 0) {
        fail(path, "XYZ file size " + std::to_string(stream.size()) +
            " is not a multiple of 12 bytes (three float32 per particle)");
    }
    ParticleSet particles;
    particles.positions.resize(size_t(stream.size() / 12));
    static_assert(sizeof(openvdb::Vec3f) == 12, "Vec3f must be three packed floats");
    unsigned char* bytes = reinterpret_cast<unsigned char*>(particles.positions.data());
    if (!stream.readBytes(bytes, particles.positions.size() * 12)) {
        // The file shrank while it was read; report what is left, as the size check would.
        fail(path, "XYZ file size " + std::to_string(stream.size()) +
            " is not a multiple of 12 bytes (three float32 per particle)");
    }
    if (kHostIsBigEndian) swapInPlace(bytes, 3 * particles.positions.size(), 4);
    return particles;
}

const char* const kParticleExtensions =
    ".vtk, .vtu, .vtp, .ply, .xyz, .bgeo, .vdb, .csv, .txt or .json";

} // namespace

ParticleSet
readParticles(const std::string& path)
{
    using namespace io_internal;
    const std::string ext = lowerExtension(path);
    if (ext.empty()) {
        throw FileError("particle file name has no extension (" + path +
            "); expected " + kParticleExtensions);
    }
    if (!isParticleFile(path)) {
        throw FileError("unknown particle file extension '" + ext + "' (" + path +
            "); expected " + kParticleExtensions);
    }

    ParticleSet particles;
    if (ext == ".vtk") {
        particles = VtkReader(path).read();
    } else if (ext == ".ply") {
        particles = PlyReader(path).read();
    } else if (ext == ".xyz") {
        particles = readXyzParticles(path);
    } else {
        // These readers work on the whole file in memory.
        const std::vector<char> file = loadFile(path);
        if (ext == ".bgeo") particles = readBgeoParticles(file.data(), file.size(), path);
        else if (ext == ".vtu" || ext == ".vtp") particles = readVtuParticles(file.data(), file.size(), path);
        else if (ext == ".csv" || ext == ".txt") particles = readTableParticles(file.data(), file.size(), path);
        else if (ext == ".json") particles = readJsonParticles(file.data(), file.size(), path);
        else particles = readVdbPointsParticles(file.data(), file.size(), path);
    }

    // Later stages hash positions into voxels; one NaN would poison the whole grid.
    for (size_t i = 0; i < particles.positions.size(); ++i) {
        const openvdb::Vec3f& p = particles.positions[i];
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
            throw ParameterError("non-finite position of particle " + std::to_string(i) +
                " (" + path + ")");
        }
    }
    return particles;
}

bool
isParticleFile(const std::string& path)
{
    const std::string ext = io_internal::lowerExtension(path);
    return ext == ".vtk" || ext == ".ply" || ext == ".xyz" || ext == ".bgeo" || ext == ".vtu"
        || ext == ".vtp" || ext == ".csv" || ext == ".txt" || ext == ".json" || ext == ".vdb";
}

} // namespace nonbloppy
