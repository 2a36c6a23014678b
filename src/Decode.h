// SPDX-License-Identifier: Apache-2.0
/// @file Decode.h
/// @brief Private byte-level decoders shared by the particle readers: gzip and zlib
///        (through zlib), base64, and big/little-endian loads. Nothing here is public API.
///
/// Every function bounds its output before allocating and reports problems as a
/// FileError "<what> (<path>)", so hostile input can neither crash nor exhaust memory.

#ifndef NONBLOPPY_DECODE_H
#define NONBLOPPY_DECODE_H

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

namespace nonbloppy {
namespace decode_internal {

/// Deflate cannot expand data by more than about 1032:1; a stream that claims more is
/// corrupt. Used to bound sizes read from headers before allocating.
constexpr uint64_t kMaxInflateRatio = 1032;

/// True if @a data starts with the gzip magic bytes 1f 8b.
bool isGzip(const char* data, size_t size);

/// Decompress the first member of a gzip stream.
/// @throw FileError "corrupt gzip data: <zlib message> (<path>)", or
///        "truncated gzip data (<path>)".
std::vector<char> gunzip(const char* data, size_t size, const std::string& path);

/// Inflate one zlib stream that must decompress to exactly @a expectedSize bytes, appended
/// to @a out. @a expectedSize must already have been checked against kMaxInflateRatio.
/// @throw FileError naming @a what (e.g. "zlib block 3 of 'velocity'").
void inflateZlib(const unsigned char* data, size_t size, size_t expectedSize,
                 std::vector<unsigned char>& out, const std::string& what,
                 const std::string& path);

/// Incremental base64 decoder over a text, as VTK writes it: whitespace is skipped, and a
/// padded quantum ('=') ends one encoded segment so the next one may start right after
/// (VTK encodes a block header and its data as two segments; other writers as one).
class Base64Reader
{
public:
    Base64Reader(std::string_view text, std::string path) : mText(text), mPath(std::move(path)) {}

    /// Append exactly @a count decoded bytes to @a out.
    /// @throw FileError "invalid base64 character ... " or "truncated base64 data in <what>".
    void read(size_t count, std::vector<unsigned char>& out, const std::string& what);
    /// Append everything left.
    void readAll(std::vector<unsigned char>& out);
    /// Upper bound of the bytes still decodable (3/4 of the characters left).
    size_t maxRemaining() const { return (mText.size() - mPos) / 4 * 3 + 3 + mPending.size(); }

private:
    bool decodeQuantum();  ///< false at the end of the text

    std::string_view mText;
    std::string mPath;
    size_t mPos = 0;
    std::vector<unsigned char> mPending;  ///< decoded but not yet returned
    size_t mPendingPos = 0;
};

/// 0..63 for base64 characters, 64 for '=', 65 for the white space VTK puts between lines,
/// 255 for anything else.
inline int base64Value(unsigned char c)
{
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    if (c == '=') return 64;
    if (c == ' ' || c == '\n' || c == '\r' || c == '\t') return 65;
    return 255;
}

/// Decode a whole base64 text (segments as in Base64Reader).
std::vector<unsigned char> decodeBase64(std::string_view text, const std::string& path,
                                        const std::string& what);

/// Reverse the bytes of each of @a count values of @a width bytes in place.
void swapBytes(unsigned char* data, size_t count, size_t width);

/// Big-endian loads (BGEO is big-endian).
inline uint32_t loadBigEndian32(const unsigned char* p)
{
    return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | uint32_t(p[3]);
}
inline uint16_t loadBigEndian16(const unsigned char* p)
{
    return uint16_t((p[0] << 8) | p[1]);
}

} // namespace decode_internal
} // namespace nonbloppy

#endif // NONBLOPPY_DECODE_H
